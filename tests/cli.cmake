# The CLI tests (tests/test_cli.cpp) run the tdcr program: build it before them.
if(TARGET test_cli AND TARGET tdcr_cli)
  add_dependencies(test_cli tdcr_cli)
endif()
