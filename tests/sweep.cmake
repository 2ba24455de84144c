# tdcr sweep: the MPI executable gives the file of a single run (tests/check_sweep_mpi.py).
if(TARGET tdcr_sweep_mpi AND TARGET tdcr_cli)
  find_program(TDCR_MPIRUN NAMES mpirun mpiexec)
  if(TDCR_MPIRUN)
    add_test(NAME sweep_mpi_equals_single_run
      COMMAND ${TDCR_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/check_sweep_mpi.py --tdcr $<TARGET_FILE:tdcr_cli>
              --mpi $<TARGET_FILE:tdcr_sweep_mpi> --mpirun ${TDCR_MPIRUN}
              --sweep ${PROJECT_SOURCE_DIR}/examples/sweeps/tension_force_grid.json --work ${PROJECT_BINARY_DIR}/sweep_mpi_test)
    set_tests_properties(sweep_mpi_equals_single_run PROPERTIES TIMEOUT 300)
  endif()
endif()
if(TARGET test_sweep AND TARGET tdcr_cli)
  add_dependencies(test_sweep tdcr_cli)
endif()
if(TARGET bench_sweep)
  add_test(NAME bench_sweep_smoke COMMAND bench_sweep --quick)
endif()
