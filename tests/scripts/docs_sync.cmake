# docs/parameters.md must be the current output of `uwbnav params --markdown`.
add_test(NAME docs_parameters_md_matches_parameter_table
  COMMAND ${CMAKE_COMMAND} -DUWBNAV=$<TARGET_FILE:uwbnav> -DDOC=${PROJECT_SOURCE_DIR}/docs/parameters.md
          -P ${CMAKE_CURRENT_LIST_DIR}/lib/check_params_doc.cmake)
