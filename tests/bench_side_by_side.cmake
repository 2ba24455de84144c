# Smoke run of the side-by-side benchmark (2 cases, 1 repeat), only in a build configured with
# TDCR_PAPER_CODE_DIR (benchmarks/paper_code); the full run is benchmarks/side_by_side.sh.
if(TARGET bench_side_by_side)
  add_test(NAME bench_side_by_side_smoke
    COMMAND bench_side_by_side --quick --out ${PROJECT_BINARY_DIR}/bench_side_by_side_smoke)
  set_tests_properties(bench_side_by_side_smoke PROPERTIES TIMEOUT 600)
endif()
