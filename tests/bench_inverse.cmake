# Smoke run of the inverse-solve benchmark (a few seconds): CCsub, PRB, VC, VCref at n = 10, unloaded
# and with a tip force; it exits 1 if a round trip misses the target or its minimum norm is not
# verified. The full matrix (benchmarks/bench_inverse.cpp) stays out of ctest.
if(TARGET bench_inverse)
  add_test(NAME bench_inverse_smoke COMMAND bench_inverse --quick --reps 1)
  set_tests_properties(bench_inverse_smoke PROPERTIES TIMEOUT 120)
endif()
