# Smoke run of the calibration benchmark (n = 5, small training sets, 20 measurements for the
# speed rows): exits 1 if a fit fails or does not lower its model's test error. The full run
# (benchmarks/bench_calibration.cpp, docs/benchmarks.md) stays out of ctest.
if(TARGET bench_calibration)
  add_test(NAME bench_calibration_smoke COMMAND bench_calibration --quick --out ${PROJECT_BINARY_DIR}/bench_calibration_smoke)
  set_tests_properties(bench_calibration_smoke PROPERTIES TIMEOUT 300)
endif()
