# The `tdcr simulate` tests (tests/test_cli_simulate.cpp) run the tdcr program: build it first.
if(TARGET test_cli_simulate AND TARGET tdcr_cli)
  add_dependencies(test_cli_simulate tdcr_cli)
endif()
