# Smoke run of the Cosserat dynamics benchmark (--quick: 0.5 s simulated, about a second);
# only where the benchmarks are built.
if(TARGET bench_dynamics_cosserat)
  add_test(NAME bench_dynamics_cosserat_smoke COMMAND bench_dynamics_cosserat --quick)
endif()
