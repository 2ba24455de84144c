# Smoke run of the VCref benchmark (seconds); the full sweep stays out of ctest.
if(TARGET bench_vcref)
  add_test(NAME bench_vcref_smoke COMMAND bench_vcref --quick)
  set_tests_properties(bench_vcref_smoke PROPERTIES TIMEOUT 120)
endif()
