# tdcr sweep: the MPI executable gives the file of a single run (tests/check_sweep_mpi.py).
if(TARGET tdcr_sweep_mpi AND TARGET tdcr_cli)
  find_program(TDCR_MPIRUN NAMES mpirun mpiexec)
  if(TDCR_MPIRUN)
    add_test(NAME sweep_mpi_equals_single_run
      COMMAND ${TDCR_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/check_sweep_mpi.py --tdcr $<TARGET_FILE:tdcr_cli>
              --mpi $<TARGET_FILE:tdcr_sweep_mpi> --mpirun ${TDCR_MPIRUN}
              --sweep ${PROJECT_SOURCE_DIR}/examples/sweeps/tension_force_grid.json --work ${PROJECT_BINARY_DIR}/sweep_mpi_test)
    set_tests_properties(sweep_mpi_equals_single_run PROPERTIES TIMEOUT 300)
    if(TDCR_SANITIZE)
      # Open MPI keeps its own allocations (MCA plugins, operator tables) past MPI_Finalize, which
      # LeakSanitizer reports from inside libmpi; address and UB checks stay on.
      set_tests_properties(sweep_mpi_equals_single_run PROPERTIES
        ENVIRONMENT "ASAN_OPTIONS=detect_leaks=0;UBSAN_OPTIONS=print_stacktrace=1")
    endif()
  endif()
endif()
if(TARGET test_sweep AND TARGET tdcr_cli)
  add_dependencies(test_sweep tdcr_cli)
endif()
if(TARGET bench_sweep)
  add_test(NAME bench_sweep_smoke COMMAND bench_sweep --quick)
endif()
# Bad input on the command line: exit status 2 and the field named, before any solve.
if(TARGET tdcr_cli)
  add_test(NAME sweep_cli_missing_sweep_file COMMAND tdcr_cli sweep ${PROJECT_BINARY_DIR}/no_such_sweep.json -o ${PROJECT_BINARY_DIR}/no_such_sweep.csv)
  set_tests_properties(sweep_cli_missing_sweep_file PROPERTIES
    PASS_REGULAR_EXPRESSION "error: sweep file: cannot read the file \\(does it exist\\?\\) \\(got [^)]*no_such_sweep.json\\)")
  # A number that overflows a double: exit 2 naming its path and text (was an internal error, exit 3).
  file(WRITE ${PROJECT_BINARY_DIR}/sweep_number_overflow.json
       "{\"scene\": \"${PROJECT_SOURCE_DIR}/examples/paper_robot_tip_force.json\", \"models\": [\"vc\"],\n"
       " \"axes\": [{\"field\": \"actuation.tensions[0]\", \"from\": 0, \"to\": 1e999, \"count\": 3}]}\n")
  add_test(NAME sweep_cli_number_overflow
           COMMAND tdcr_cli sweep ${PROJECT_BINARY_DIR}/sweep_number_overflow.json -o ${PROJECT_BINARY_DIR}/sweep_number_overflow.csv)
  set_tests_properties(sweep_cli_number_overflow PROPERTIES
    PASS_REGULAR_EXPRESSION "error: axes\\[0\\]\\.to: must be a finite number [^\n]*\\(got 1e999\\)")
  add_test(NAME sweep_cli_bad_shard COMMAND tdcr_cli sweep ${PROJECT_SOURCE_DIR}/examples/sweeps/tension_force_grid.json -o x.csv --shard 2/2)
  set_tests_properties(sweep_cli_bad_shard PROPERTIES PASS_REGULAR_EXPRESSION "--shard: must be a whole number from 0 to 1 \\(got 2\\)")
endif()
