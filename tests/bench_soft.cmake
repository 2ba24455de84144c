# bench_soft's smoke run (one soft scene, every static model, one cold solve each); the full
# table is made by benchmarks/run_all.sh, never by ctest.
if(TARGET bench_soft)
  add_test(NAME bench_soft_smoke COMMAND bench_soft --quick --out ${PROJECT_BINARY_DIR}/bench_soft_smoke)
  set_tests_properties(bench_soft_smoke PROPERTIES TIMEOUT 120)
endif()
if(TARGET bench_soft)
  # The same with accuracy-driven RK4 for VC and VCref (soft_tol.csv).
  add_test(NAME bench_soft_tol_smoke COMMAND bench_soft --quick --rk4-tip-tol 1e-8 --out ${PROJECT_BINARY_DIR}/bench_soft_smoke)
  set_tests_properties(bench_soft_tol_smoke PROPERTIES TIMEOUT 120)
endif()
