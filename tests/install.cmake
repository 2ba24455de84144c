# A research code links tdcr through find_package(tdcr): install into a temporary prefix and build
# the research-program example (examples/research_program) against it, then run it.
add_test(NAME install_find_package
  COMMAND ${CMAKE_COMMAND} -DBIN=${PROJECT_BINARY_DIR} -DSRC=${PROJECT_SOURCE_DIR}/examples/research_program
          -DWORK=${PROJECT_BINARY_DIR}/install_test -P ${CMAKE_CURRENT_SOURCE_DIR}/install_consumer/run.cmake)
set_tests_properties(install_find_package PROPERTIES TIMEOUT 600
  PASS_REGULAR_EXPRESSION "research_program: VC vs VCref tip error = [0-9.]+ % of length")
