# Architecture rules as a test: estimator/ is a pure library (no hal/ or firmware/
# includes, no I/O or OS headers, no heap, no function-local statics).
add_test(NAME layout_estimator_is_pure_library
  COMMAND ${CMAKE_COMMAND} -DSRC=${PROJECT_SOURCE_DIR} -P ${CMAKE_CURRENT_LIST_DIR}/lib/check_layout.cmake)
