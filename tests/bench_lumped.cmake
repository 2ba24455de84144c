# Smoke run of the lumped-model benchmark (--quick: seconds); only where the benchmarks are built.
if(TARGET bench_lumped)
  add_test(NAME bench_lumped_smoke COMMAND bench_lumped --quick)
endif()
