# docs/results must agree with the code: regenerate the tables of one small
# simulated recording and one real one shipped in data/ and compare
# with the committed numbers within noise (tests/scripts/lib/check_results.py).
add_test(NAME results_committed_tables_match_the_code
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/lib/check_results.py
          --uwbnav $<TARGET_FILE:uwbnav> --docs ${PROJECT_SOURCE_DIR}/docs/results
          --data ${UWBNAV_DATA_DIR} --work ${PROJECT_BINARY_DIR}/results_check)
set_tests_properties(results_committed_tables_match_the_code PROPERTIES SKIP_RETURN_CODE 77 TIMEOUT 600)
