# Every example scene is a regression test with its expected answer (examples/expected/), as the
# examples of SUNDIALS carry answer files. Regenerate after an intended change with
#   python3 tests/check_example.py build/bin/tdcr examples/X.json examples/expected/X.json --update
file(GLOB TDCR_EXAMPLE_SCENES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/examples/*.json)
foreach(scene ${TDCR_EXAMPLE_SCENES})
  get_filename_component(name ${scene} NAME_WE)
  add_test(NAME example_${name}
           COMMAND ${TDCR_PYTHON3} ${CMAKE_CURRENT_SOURCE_DIR}/check_example.py $<TARGET_FILE:tdcr_cli> ${scene}
                   ${PROJECT_SOURCE_DIR}/examples/expected/${name}.json)
endforeach()
# The dynamics example also runs as a simulation (2 s of the paper robot's tension step).
add_test(NAME example_paper_robot_dynamics_simulate
         COMMAND tdcr_cli simulate ${PROJECT_SOURCE_DIR}/examples/paper_robot_dynamics.json --duration 2
                 -o ${CMAKE_CURRENT_BINARY_DIR}/paper_robot_dynamics.csv)
# And its displacement-driven twin (VC: tendon 1 pulled by 2 mm within 50 ms, held).
add_test(NAME example_dynamics_displacement_simulate
         COMMAND tdcr_cli simulate ${PROJECT_SOURCE_DIR}/examples/dynamics_displacement.json --duration 2
                 -o ${CMAKE_CURRENT_BINARY_DIR}/dynamics_displacement.npz)
# Motors on elastic tendons in CCsub's and PRB's dynamics (docs/dynamics.md, "Displacement input").
foreach(model ccsub prb)
  add_test(NAME example_dynamics_motors_elastic_simulate_${model}
           COMMAND tdcr_cli simulate ${PROJECT_SOURCE_DIR}/examples/dynamics_motors_elastic.json --duration 2
                   --model ${model} -o ${CMAKE_CURRENT_BINARY_DIR}/dynamics_motors_elastic_${model}.csv)
endforeach()
