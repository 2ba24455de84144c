# Memcheck of the displacement-input solve: the CLI solves a co-contracted displacement scene
# (tests/data/displacement_co_contraction.json) under valgrind, which fails the test on any read
# of uninitialised memory or invalid access (--error-exitcode). The displacement solve once took
# its Newton steps from Eigen's CompleteOrthogonalDecomposition, whose solve of a rank-deficient
# matrix read uninitialised memory: the same scene file then gave other tensions depending on how
# its path was spelled. Not under the sanitizers (valgrind cannot run an ASan build).
if(TARGET tdcr_cli AND NOT TDCR_SANITIZE)
  find_program(TDCR_VALGRIND valgrind)
  if(TDCR_VALGRIND)
    foreach(model ccsub prb)
      add_test(NAME memcheck_displacement_input_${model}
               COMMAND ${TDCR_VALGRIND} --quiet --error-exitcode=1 --errors-for-leak-kinds=none
                       $<TARGET_FILE:tdcr_cli> solve ${CMAKE_CURRENT_SOURCE_DIR}/data/displacement_co_contraction.json
                       --model ${model})
      set_tests_properties(memcheck_displacement_input_${model} PROPERTIES TIMEOUT 300)
    endforeach()
  else()
    message(STATUS "valgrind not found: the memcheck tests are not registered")
  endif()
endif()
