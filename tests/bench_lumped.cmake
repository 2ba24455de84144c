# Smoke run of the lumped-model benchmark (--quick: seconds); only where the benchmarks are built.
if(TARGET bench_lumped)
  add_test(NAME bench_lumped_smoke COMMAND bench_lumped --quick)
endif()
# Smoke run of the dynamics benchmark (0.1 s of motion).
if(TARGET bench_dynamics)
  add_test(NAME bench_dynamics_smoke COMMAND bench_dynamics --quick)
endif()
