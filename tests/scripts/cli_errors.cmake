# The CLI never misleads (issue 18): unreadable input is named with file, line
# and reason; no solution or an early-ended input stream exits non-zero; a
# failed command leaves no output directory; --help on every command exits 0
# with its usage; parameter errors name the parameter and the reason in the
# console's words (firmware/param_text.hpp). Each test runs lib/check_cli.cmake.
if(TARGET uwbnav)
  set(cli_dir ${PROJECT_BINARY_DIR}/tests/cli)
  file(WRITE ${cli_dir}/small.scn [=[
[scenario]
name = cli_small
description = 4 anchors, IMU and UWB, 20 s (CLI error tests)
duration_s = 20
platform = ground
[site]
anchor = 1 0 0 1.5
anchor = 2 10 0 1.5
anchor = 3 10 8 1.5
anchor = 4 0 8 1.5
tag = 0 0 0 0.5
[imu]
enabled = 1
rate_hz = 100
[uwb]
rate_hz = 20
sigma_m = 0.1
packet_loss = 0
channel_diagnostics = 0
[nlos]
body_block = 0
outlier_prob = 0
[route]
start = 2 2 0 0
loop_from = 1
maneuver = hold 3
maneuver = speed 1.0 2
maneuver = hold 2
maneuver = turn 90 3
]=])
  add_test(NAME cli_sim_small_recording COMMAND uwbnav sim ${cli_dir}/small.scn --seed 2 --out ${cli_dir}/rec)
  set_tests_properties(cli_sim_small_recording PROPERTIES FIXTURES_SETUP cli_rec)

  set(check -DUWBNAV=$<TARGET_FILE:uwbnav> -P ${CMAKE_CURRENT_LIST_DIR}/lib/check_cli.cmake)
  # name, then -D arguments for check_cli.cmake
  function(cli_check name)
    add_test(NAME ${name} COMMAND ${CMAKE_COMMAND} ${ARGN} ${check})
    set_tests_properties(${name} PROPERTIES FIXTURES_REQUIRED cli_rec)
  endfunction()

  cli_check(cli_replay_good_recording_exits_0
    "-DARGS=replay|${cli_dir}/rec|--out|${cli_dir}/good" -DRC=0 "-DOUT=uwbnav EKF")
  cli_check(cli_replay_missing_dir_names_it_and_leaves_no_output
    "-DARGS=replay|${cli_dir}/no_such_rec|--out|${cli_dir}/o_missing" -DRC=1
    "-DERR=no_such_rec: no such directory" -DABSENT=${cli_dir}/o_missing)
  cli_check(cli_replay_empty_dir_names_the_missing_file
    "-DPREPARE=mkdir|${cli_dir}/empty"
    "-DARGS=replay|${cli_dir}/empty|--out|${cli_dir}/o_empty" -DRC=1
    "-DERR=cannot read recording .*empty: anchors.csv: required file missing" -DABSENT=${cli_dir}/o_empty)
  cli_check(cli_replay_wrong_imu_header_names_file_line_and_reason
    "-DPREPARE=copy|${cli_dir}/rec|${cli_dir}/bad_header" "-DEDIT=replace|imu.csv|t_s,ax,ay,az\\n1.0,0,0,9.8\\n"
    "-DARGS=replay|${cli_dir}/bad_header|--out|${cli_dir}/o_header" -DRC=1
    "-DERR=cannot read recording .*bad_header: imu.csv:1: " -DABSENT=${cli_dir}/o_header)
  cli_check(cli_replay_corrupt_anchors_warns_per_line_and_exits_3_without_solution
    "-DPREPARE=copy|${cli_dir}/rec|${cli_dir}/bad_anchors"
    "-DEDIT=replace|anchors.csv|anchor_id,x_m,y_m,z_m\\n1,0,0,1.5\\n2,1O,0,1.5\\n3,10,8,\\n4,0,eight,1.5\\n"
    "-DARGS=replay|${cli_dir}/bad_anchors|--out|${cli_dir}/o_anchors" -DRC=3
    "-DERR=anchors.csv:3: .*anchors.csv:4: .*anchors.csv:5: .*no solution: 0 of [0-9]+ epochs")
  cli_check(cli_replay_truncated_imu_exits_3_naming_the_stream
    "-DPREPARE=copy|${cli_dir}/rec|${cli_dir}/short_imu" "-DEDIT=truncate_half|imu.csv"
    "-DARGS=replay|${cli_dir}/short_imu|--out|${cli_dir}/o_short" -DRC=3
    "-DERR=imu.csv: ends at t=[0-9.]+ s, [0-9.]+ s before uwb.csv .*input stream ended early")

  # Streaming replay (issue 17): damage met mid-stream is still named with file and line.
  cli_check(cli_replay_bad_row_mid_stream_names_file_and_line
    "-DPREPARE=copy|${cli_dir}/rec|${cli_dir}/bad_row" "-DEDIT=replace_line|imu.csv|1000|abc,0,0,9.8,0,0,0"
    "-DARGS=replay|${cli_dir}/bad_row|--out|${cli_dir}/o_bad_row" -DRC=0 "-DOUT=uwbnav EKF"
    "-DERR=warning: imu.csv:1000: t_s: unparsable number 'abc'.*warning: 1 bad rows skipped")
  cli_check(cli_eval_report_truncated_imu_exits_3_naming_the_stream
    "-DPREPARE=copy|${cli_dir}/rec|${cli_dir}/short_imu_eval" "-DEDIT=truncate_half|imu.csv"
    "-DARGS=eval|report|${cli_dir}/short_imu_eval|--out|${cli_dir}/o_short_eval|--no-figures|--jobs|1" -DRC=3
    "-DERR=short_imu_eval: imu.csv: ends at t=[0-9.]+ s, [0-9.]+ s before uwb.csv .*input stream ended early")

  cli_check(cli_firmware_truncated_imu_warns_and_exits_3
    "-DPREPARE=copy|${cli_dir}/rec|${cli_dir}/short_imu_fw" "-DEDIT=truncate_half|imu.csv"
    "-DARGS=firmware|--recording|${cli_dir}/short_imu_fw|--console|none|--duration|0.5" -DRC=3
    "-DERR=warning: imu.csv: ends at t=.*input stream ended early")

  # Parameters: which one and why, the same words as the console's `param set`.
  cli_check(cli_replay_param_not_a_number
    "-DARGS=replay|${cli_dir}/rec|--out|${cli_dir}/o_p1|--param|uwb.sigma=abc" -DRC=2
    "-DERR=^uwbnav replay: param: uwb.sigma=abc is not a finite number\n$" -DABSENT=${cli_dir}/o_p1)
  cli_check(cli_replay_param_fraction_of_enum_refused
    "-DARGS=replay|${cli_dir}/rec|--out|${cli_dir}/o_p2|--param|gate.policy=3.5" -DRC=2
    "-DERR=param: gate.policy=3.5 is not a whole number \\(enum parameter\\)" -DABSENT=${cli_dir}/o_p2)
  cli_check(cli_replay_param_unknown
    "-DARGS=replay|${cli_dir}/rec|--out|${cli_dir}/o_p3|--param|uwb.sigmaa=1" -DRC=2
    "-DERR=param: unknown parameter 'uwb.sigmaa' \\(see param list\\)" -DABSENT=${cli_dir}/o_p3)
  cli_check(cli_replay_param_without_equals
    "-DARGS=replay|${cli_dir}/rec|--out|${cli_dir}/o_p4|--param|uwb.sigma" -DRC=2
    "-DERR=param: 'uwb.sigma' is not NAME=VALUE")
  cli_check(cli_firmware_param_out_of_range_names_bounds
    "-DARGS=firmware|--recording|${cli_dir}/rec|--console|none|--duration|1|--param|uwb.sigma=9" -DRC=2
    "-DERR=^uwbnav firmware: param: uwb.sigma=9 out of range \\[0.01, 5\\]\n$")
  cli_check(cli_firmware_param_fraction_of_bool_refused
    "-DARGS=firmware|--recording|${cli_dir}/rec|--console|none|--duration|1|--param|can.tx_enable=0.5" -DRC=2
    "-DERR=param: can.tx_enable=0.5 is not a whole number \\(bool parameter\\)")
  cli_check(cli_eval_family_param_same_wording
    "-DARGS=eval|family|--param|gate.policy=3.5" -DRC=2
    "-DERR=^uwbnav eval family: param: gate.policy=3.5 is not a whole number \\(enum parameter\\)\n$")

  # --cpu: the loop thread pinned to one CPU, or refused naming the CPUs there are.
  cli_check(cli_firmware_cpu_outside_the_allowed_set_refused
    "-DARGS=firmware|--recording|${cli_dir}/rec|--console|none|--duration|0.5|--cpu|1000" -DRC=2
    "-DERR=^uwbnav firmware: --cpu 1000: not one of the CPUs this process may use \\([0-9,-]+\\)\n$")
  cli_check(cli_firmware_cpu_not_a_number_is_a_usage_error
    "-DARGS=firmware|--recording|${cli_dir}/rec|--console|none|--duration|0.5|--cpu|x" -DRC=2
    "-DERR=usage: uwbnav firmware")
  cli_check(cli_firmware_cpu_0_pins_the_loop_thread
    "-DARGS=firmware|--recording|${cli_dir}/rec|--console|none|--duration|0.5|--no-rt|--cpu|0" -DRC=0
    "-DOUT=firmware: loop thread pinned to CPU 0\n.*  cpu      loop thread pinned to CPU 0\n")

  # stdio console: end of input ends the session cleanly, after the replies went out.
  file(WRITE ${cli_dir}/console_input.txt "status\nparam list -c\nparam set uwb.sigma 0.2\nparam list -c\n")
  cli_check(cli_firmware_stdio_console_ends_the_session_at_end_of_input
    "-DARGS=firmware|--recording|${cli_dir}/rec" -DINPUT=${cli_dir}/console_input.txt -DRC=0
    "-DOUT=status t_us=.*operator_resets=0 .*param count=0.*param name=uwb.sigma value=0.2 old=0.1.*param count=1.*stopped \\(end of console input\\)")

  # Help: exit 0, usage on stdout, for every command (and eval's subcommands).
  cli_check(cli_help_lists_commands "-DARGS=help" -DRC=0 "-DOUT=usage: uwbnav <command>.*replay")
  foreach(cmd run sim replay eval train-svm firmware hil params calibrate)
    cli_check(cli_${cmd}_help_exits_0_with_usage "-DARGS=${cmd}|--help" -DRC=0 "-DOUT=usage: uwbnav ${cmd}"
      "-DNOT_OUT=unknown option")
    cli_check(cli_help_${cmd}_exits_0_with_usage "-DARGS=help|${cmd}" -DRC=0 "-DOUT=usage: uwbnav ${cmd}")
  endforeach()
  foreach(sub report nlos family)
    cli_check(cli_eval_${sub}_help_exits_0_with_usage "-DARGS=eval|${sub}|--help" -DRC=0 "-DOUT=usage: uwbnav eval ${sub}"
      "-DNOT_OUT=unknown option")
  endforeach()
  cli_check(cli_replay_help_after_arguments_exits_0
    "-DARGS=replay|${cli_dir}/rec|--out|${cli_dir}/o_help|--help" -DRC=0 "-DOUT=usage: uwbnav replay" -DABSENT=${cli_dir}/o_help)
endif()
