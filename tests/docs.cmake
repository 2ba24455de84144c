# docs_no_warnings: the Doxygen documentation must build without a single warning, so that CI
# fails on any new one (an undocumented public member, a broken \ref, a bad Markdown page).
#
# This file has two roles:
#  - included by tests/CMakeLists.txt, it registers the test (only if Doxygen is found);
#  - run by the test as `cmake -P tests/docs.cmake`, it builds the `docs` target
#    (docs/CMakeLists.txt) and fails, printing the log, if Doxygen's warning log is not empty.
if(NOT CMAKE_SCRIPT_MODE_FILE)
  find_package(Doxygen QUIET)
  if(DOXYGEN_FOUND)
    add_test(NAME docs_no_warnings
      COMMAND ${CMAKE_COMMAND} -DTDCR_BINARY_DIR=${PROJECT_BINARY_DIR}
              -DTDCR_WARN_LOG=${PROJECT_BINARY_DIR}/docs/doxygen-warnings.txt
              -P ${CMAKE_CURRENT_LIST_FILE})
    # A few seconds (HTML and graphs of the public headers); the bound only guards a hang.
    set_tests_properties(docs_no_warnings PROPERTIES TIMEOUT 120)
  else()
    message(STATUS "Doxygen not found: test docs_no_warnings not registered")
  endif()
  return()
endif()

# Script mode.
foreach(var TDCR_BINARY_DIR TDCR_WARN_LOG)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "docs.cmake: -D${var}=... is required")
  endif()
endforeach()

# A stale log must not hide a Doxygen run that did not happen.
file(REMOVE ${TDCR_WARN_LOG})
execute_process(COMMAND ${CMAKE_COMMAND} --build ${TDCR_BINARY_DIR} --target docs
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the docs target failed (${rc}):\n${out}\n${err}")
endif()
if(NOT EXISTS ${TDCR_WARN_LOG})
  message(FATAL_ERROR "Doxygen wrote no warning log ${TDCR_WARN_LOG}:\n${out}\n${err}")
endif()

file(READ ${TDCR_WARN_LOG} log)
string(STRIP "${log}" log)
if(NOT log STREQUAL "")
  string(REGEX MATCHALL "(warning|error): " hits "${log}")
  list(LENGTH hits count)
  # The log verbatim (a FATAL_ERROR message would re-wrap its lines), then the verdict.
  message("${log}\n")
  message(FATAL_ERROR "Doxygen reported ${count} warning(s), listed above (${TDCR_WARN_LOG}); "
                      "document the public API and fix the pages until the log is empty.")
endif()
message(STATUS "Doxygen: no warnings")
