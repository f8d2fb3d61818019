# `uwbnav eval family --fast` end to end: the table is produced for the chosen
# cells with the seed set named, and `uwbnav sim family:CELL:SEED` writes a
# replayable recording (tests/scripts/lib/check_eval_family.cmake).
add_test(NAME eval_family_fast_subset_prints_the_tables
  COMMAND ${CMAKE_COMMAND} -DUWBNAV=$<TARGET_FILE:uwbnav> -DWORK=${PROJECT_BINARY_DIR}/eval_family_check
          -P ${CMAKE_CURRENT_LIST_DIR}/lib/check_eval_family.cmake)
set_tests_properties(eval_family_fast_subset_prints_the_tables PROPERTIES TIMEOUT 600)
