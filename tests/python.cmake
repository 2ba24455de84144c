# The Python module (python/): its pytest suite, the Python examples and `tdcr plot`, each run with
# PYTHONPATH at the build tree's package. Registered when the module and the CLI are built.
if(TARGET tdcr_python AND TARGET tdcr_cli)
  set(TDCR_PY_ENV "PYTHONPATH=${TDCR_PYTHON_BUILD_DIR}" "TDCR_CLI=$<TARGET_FILE:tdcr_cli>"
                  "TDCR_SOURCE_DIR=${PROJECT_SOURCE_DIR}" "MPLBACKEND=Agg")
  add_test(NAME python_pytest
           COMMAND ${TDCR_PYTHON_EXECUTABLE} -m pytest -q -p no:cacheprovider ${PROJECT_SOURCE_DIR}/python/tests
           WORKING_DIRECTORY ${PROJECT_BINARY_DIR})
  set_tests_properties(python_pytest PROPERTIES ENVIRONMENT "${TDCR_PY_ENV}" TIMEOUT 300)
  foreach(example trajectory_warm_start compare_models)
    add_test(NAME python_example_${example}
             COMMAND ${TDCR_PYTHON_EXECUTABLE} ${PROJECT_SOURCE_DIR}/examples/python/${example}.py
                     ${PROJECT_SOURCE_DIR}/examples/paper_robot_vc.json
             WORKING_DIRECTORY ${PROJECT_BINARY_DIR})
    set_tests_properties(python_example_${example} PROPERTIES ENVIRONMENT "${TDCR_PY_ENV}" TIMEOUT 120)
  endforeach()
  # `cmake --install`: the module under the prefix imports, the installed `tdcr plot` finds it.
  add_test(NAME python_install
           COMMAND ${CMAKE_COMMAND} -DBIN=${PROJECT_BINARY_DIR} -DWORK=${PROJECT_BINARY_DIR}/python_install_test
                   -DPYDIR=${TDCR_PYTHON_INSTALL_DIR} -DPYTHON=${TDCR_PYTHON_EXECUTABLE}
                   -DSCENE=${PROJECT_SOURCE_DIR}/examples/paper_robot_vc.json
                   -P ${PROJECT_SOURCE_DIR}/python/tests/check_install.cmake)
  set_tests_properties(python_install PROPERTIES TIMEOUT 300)
  # `tdcr plot` end to end: a PNG and an SVG of two models, checked by their magic / root tag.
  add_test(NAME cli_plot
           COMMAND ${CMAKE_COMMAND} -DCLI=$<TARGET_FILE:tdcr_cli> -DSCENE=${PROJECT_SOURCE_DIR}/examples/paper_robot_tip_force.json
                   -DWORK=${PROJECT_BINARY_DIR}/plot_test -P ${PROJECT_SOURCE_DIR}/python/tests/check_plot.cmake)
  set_tests_properties(cli_plot PROPERTIES TIMEOUT 120)
endif()
