# Smoke run of the case-study benchmark (seconds): checks that every table is written, well formed,
# and its errors finite (tests/check_bench_output.py). The full sweep stays out of ctest.
if(TARGET bench_case_study)
  add_test(NAME bench_case_study_smoke
    COMMAND ${CMAKE_COMMAND} -E env
      ${TDCR_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/check_bench_output.py
      $<TARGET_FILE:bench_case_study> ${PROJECT_BINARY_DIR}/bench_smoke ${PROJECT_SOURCE_DIR}/benchmarks/plot_results.py)
  set_tests_properties(bench_case_study_smoke PROPERTIES TIMEOUT 600)
endif()
