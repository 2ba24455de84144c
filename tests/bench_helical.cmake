# Smoke run of the helical-routing benchmark (scenario 3, the disk force, the disk count a design
# needs; --quick: a few seconds); the full sweep stays out of ctest (benchmarks/run_all.sh).
if(TARGET bench_helical)
  add_test(NAME bench_helical_smoke
    COMMAND bench_helical --quick --out ${PROJECT_BINARY_DIR}/bench_helical_smoke)
  set_tests_properties(bench_helical_smoke PROPERTIES TIMEOUT 600)
endif()
