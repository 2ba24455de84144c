add_test(NAME bench_vc_smoke COMMAND bench_vc --quick)
