# Driven by ctest (tests/python.cmake, test python_install): `cmake --install` puts the module under
# the prefix; it imports from there, and the installed `tdcr plot` finds it without PYTHONPATH.
file(REMOVE_RECURSE ${WORK})
function(run)
  execute_process(COMMAND ${ARGV} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGV}\n${out}\n${err}")
  endif()
  set(out "${out}" PARENT_SCOPE)
endfunction()
run(${CMAKE_COMMAND} --install ${BIN} --prefix ${WORK}/prefix)
run(${CMAKE_COMMAND} -E env PYTHONPATH=${WORK}/prefix/${PYDIR}
    ${PYTHON} -c "import tdcr\nprint(tdcr.__file__)\nprint(tdcr.solve('${SCENE}').tip_position)")  # no ';': a CMake list separator
if(NOT out MATCHES "${WORK}/prefix/")
  message(FATAL_ERROR "tdcr was not imported from the prefix:\n${out}")
endif()
run(${CMAKE_COMMAND} -E env --unset=PYTHONPATH ${WORK}/prefix/bin/tdcr plot ${SCENE} -o ${WORK}/robot.svg)
if(NOT EXISTS ${WORK}/robot.svg)
  message(FATAL_ERROR "the installed tdcr plot wrote no picture")
endif()
message("installed module: ${out}")
