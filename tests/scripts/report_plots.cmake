# tools/plot/report_plots.py: error_time.png is scaled to the filter's error,
# not to the LS baseline's spikes (tests/scripts/test_report_plots.py).
add_test(NAME report_plots_error_time_scales_to_the_filter
  COMMAND /usr/bin/python3 ${CMAKE_CURRENT_LIST_DIR}/test_report_plots.py ${PROJECT_SOURCE_DIR}
          ${PROJECT_BINARY_DIR}/tests/report_plots)
