# docs/dataset-format.md must stay identical to the shared format v1 spec.
# Included by tests/CMakeLists.txt: registers the test. Run with `cmake -P`
# (by that test): compares the files, or passes with a skip note when the
# shared copy is absent.
if(NOT CMAKE_SCRIPT_MODE_FILE)
  add_test(NAME dataset_spec_in_sync_with_shared
    COMMAND ${CMAKE_COMMAND}
            -DPROJECT_SPEC=${PROJECT_SOURCE_DIR}/docs/dataset-format.md
            -DSHARED_SPEC=${UWBNAV_SHARED_DIR}/docs/dataset-format.md
            -P ${CMAKE_CURRENT_LIST_FILE})
  set_tests_properties(dataset_spec_in_sync_with_shared PROPERTIES
    SKIP_REGULAR_EXPRESSION "SKIP dataset_spec_in_sync_with_shared")
  return()
endif()

if(NOT EXISTS "${SHARED_SPEC}")
  message(STATUS "SKIP dataset_spec_in_sync_with_shared: shared spec ${SHARED_SPEC} absent")
  return()
endif()
if(NOT EXISTS "${PROJECT_SPEC}")
  message(FATAL_ERROR "${PROJECT_SPEC} missing: copy ${SHARED_SPEC} into docs/")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} -E compare_files "${PROJECT_SPEC}" "${SHARED_SPEC}" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "${PROJECT_SPEC} differs from ${SHARED_SPEC}: the format v1 spec changed, "
                      "update docs/dataset-format.md and the reader/writer in tools/dataset/")
endif()
message(STATUS "docs/dataset-format.md matches ${SHARED_SPEC}")
