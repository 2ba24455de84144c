# models_layers: the models layer's includes point one way (services -> models -> solve -> physics
# -> bvp, core; no model folder includes another's but lumped/), checked on the source tree by
# tests/check_layers.py, which names any include against them.
add_test(NAME models_layers COMMAND ${TDCR_PYTHON3} ${CMAKE_CURRENT_LIST_DIR}/check_layers.py ${PROJECT_SOURCE_DIR})
set_tests_properties(models_layers PROPERTIES TIMEOUT 60)
