add_test(NAME bench_lumped_smoke COMMAND bench_lumped --quick)
