# Smoke run of the loaded benchmark (2 cases, 1 repeat, 20 trajectory steps: seconds); the full
# run (60 cases, 1000 steps) stays out of ctest.
if(TARGET bench_loaded)
  add_test(NAME bench_loaded_smoke
    COMMAND bench_loaded --quick --out ${PROJECT_BINARY_DIR}/bench_loaded_smoke)
  set_tests_properties(bench_loaded_smoke PROPERTIES TIMEOUT 600)  # 1.3 s in Release, 100 s under ASan
  # The same with every timed solve after a cache eviction (the option that times cold starts).
  add_test(NAME bench_loaded_evict_caches_smoke
    COMMAND bench_loaded --quick --models ccsub --evict-caches --out ${PROJECT_BINARY_DIR}/bench_loaded_evict_smoke)
  set_tests_properties(bench_loaded_evict_caches_smoke PROPERTIES TIMEOUT 600)
endif()
