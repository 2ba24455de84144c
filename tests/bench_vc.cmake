# Smoke run of the VC benchmark (--quick: seconds); only where the benchmarks are built.
if(TARGET bench_vc)
  add_test(NAME bench_vc_smoke COMMAND bench_vc --quick)
endif()
