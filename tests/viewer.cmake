# The viewer (tdcr view) in a real browser: Debian's chromium, headless, driven by playwright-core
# (viewer/tests/check_viewer.mjs; .ci/deps installs chromium and the npm packages of viewer/).
#  - viewer_browser: the page draws the robot (screenshot), a slider move gives tdcr solve's tip, a
#    bad scene shows its error on the page, the server refuses anything but the loopback;
#  - viewer_latency_smoke: a short run of the latency benchmark (benchmarks/bench_viewer.sh).
# Registered with the Python module and the CLI, and where Node.js is found.
find_program(TDCR_NODE node)
if(TARGET tdcr_python AND TARGET tdcr_cli AND TDCR_NODE)
  add_test(NAME viewer_browser
           COMMAND ${TDCR_NODE} ${PROJECT_SOURCE_DIR}/viewer/tests/check_viewer.mjs
                   --cli $<TARGET_FILE:tdcr_cli> --scene ${PROJECT_SOURCE_DIR}/examples/paper_robot_vc.json
                   --bad-scene ${CMAKE_CURRENT_LIST_DIR}/data/bad_scene_negative_length.json
                   --out ${PROJECT_BINARY_DIR}/viewer_test)
  add_test(NAME viewer_latency_smoke
           COMMAND ${TDCR_NODE} ${PROJECT_SOURCE_DIR}/viewer/tests/check_viewer.mjs
                   --cli $<TARGET_FILE:tdcr_cli> --scene ${PROJECT_SOURCE_DIR}/examples/paper_robot_vc.json
                   --out ${PROJECT_BINARY_DIR}/viewer_test --bench ccsub,vc --moves 5)
  set_tests_properties(viewer_browser viewer_latency_smoke PROPERTIES TIMEOUT 180 RUN_SERIAL TRUE)
elseif(TARGET tdcr_python AND TARGET tdcr_cli)
  message(WARNING "Node.js not found: the viewer's browser tests are not registered (bash .ci/deps installs it)")
endif()
