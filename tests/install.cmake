# A research code links tdcr through find_package(tdcr): install into a temporary prefix and
# build a tiny outside project against it (tests/install_consumer).
add_test(NAME install_find_package
  COMMAND ${CMAKE_COMMAND} -DBIN=${PROJECT_BINARY_DIR} -DSRC=${CMAKE_CURRENT_SOURCE_DIR}/install_consumer
          -DWORK=${PROJECT_BINARY_DIR}/install_test -P ${CMAKE_CURRENT_SOURCE_DIR}/install_consumer/run.cmake)
set_tests_properties(install_find_package PROPERTIES TIMEOUT 600 PASS_REGULAR_EXPRESSION "consumer: tip z = 0\\.0[0-9]+")
