# The `tdcr calibrate` tests (tests/test_cli_calibrate.cpp) run the tdcr program: build it first.
if(TARGET test_cli_calibrate AND TARGET tdcr_cli)
  add_dependencies(test_cli_calibrate tdcr_cli)
endif()
