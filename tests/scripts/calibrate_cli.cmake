# Commissioning end to end through the CLI (docs/commissioning.md): simulate a
# 3-tag trolley, `uwbnav calibrate` writes the site calibration file, replay
# and the firmware process load it with --cal (and refuse a broken one with
# file:line: reason), self-calibration agrees with the truth-based file.
if(TARGET uwbnav)
  set(cal_dir ${PROJECT_BINARY_DIR}/tests/calibrate)
  file(WRITE ${cal_dir}/trolley.scn [=[
[scenario]
name = trolley_cli
description = 3-tag trolley, 8 anchors at 1.04 m, UWB only, 100 Hz (calibrate CLI test)
duration_s = 40
platform = ground
[site]
anchor = 1 0 0 1.04
anchor = 2 4 0 1.04
anchor = 3 8 0 1.04
anchor = 4 8 3 1.04
anchor = 5 8 6 1.04
anchor = 6 4 6 1.04
anchor = 7 0 6 1.04
anchor = 8 0 3 1.04
tag = 0 0.20 0 0.45
tag = 1 -0.10 0.15 0.45
tag = 2 -0.10 -0.15 0.45
[imu]
enabled = 0
rate_hz = 100
[uwb]
rate_hz = 100
sigma_m = 0.05
packet_loss = 0
channel_diagnostics = 0
[nlos]
body_block = 0
outlier_prob = 0
[route]
start = 1.5 1.2 0 0
loop_from = 2
maneuver = hold 5
maneuver = speed 0.8 2
maneuver = hold 1.5
maneuver = turn 90 3
maneuver = hold 0.5
maneuver = turn 90 3
maneuver = hold 1.5
maneuver = turn 90 3
maneuver = hold 0.5
maneuver = turn 90 3
]=])
  file(WRITE ${cal_dir}/broken.cal
    "# uwbnav range calibration v1\nsite_sigma_m = 0.01\nanchor_id,tag_id,offset_m,sigma_m\n1,0,nan,0.01\n")

  add_test(NAME calibrate_cli_sim_trolley
    COMMAND uwbnav sim ${cal_dir}/trolley.scn --seed 4 --out ${cal_dir}/rec)
  set_tests_properties(calibrate_cli_sim_trolley PROPERTIES FIXTURES_SETUP cal_rec)

  add_test(NAME calibrate_cli_writes_site_file_from_truth
    COMMAND uwbnav calibrate ${cal_dir}/rec --out ${cal_dir}/site.cal)
  set_tests_properties(calibrate_cli_writes_site_file_from_truth PROPERTIES
    FIXTURES_REQUIRED cal_rec FIXTURES_SETUP cal_file
    PASS_REGULAR_EXPRESSION "method truth, 24 pairs .*observability: every offset determined.*wrote .*site\\.cal \\(24 pairs")

  add_test(NAME calibrate_cli_self_calibration_agrees_with_truth_file
    COMMAND uwbnav calibrate ${cal_dir}/rec --method self --compare ${cal_dir}/site.cal)
  set_tests_properties(calibrate_cli_self_calibration_agrees_with_truth_file PROPERTIES
    FIXTURES_REQUIRED cal_file
    PASS_REGULAR_EXPRESSION "difference: max 0\\.0[01][0-9]+ m")

  add_test(NAME calibrate_cli_replay_loads_the_file
    COMMAND uwbnav replay ${cal_dir}/rec --out ${cal_dir}/replay --cal ${cal_dir}/site.cal)
  set_tests_properties(calibrate_cli_replay_loads_the_file PROPERTIES
    FIXTURES_REQUIRED cal_file
    PASS_REGULAR_EXPRESSION "calibration: .*site\\.cal \\(8 anchors x 3 tags, site sigma 0\\.00[0-9]+ m\\)")

  add_test(NAME calibrate_cli_replay_refuses_a_broken_file_with_file_line_reason
    COMMAND uwbnav replay ${cal_dir}/rec --out ${cal_dir}/replay_broken --cal ${cal_dir}/broken.cal)
  set_tests_properties(calibrate_cli_replay_refuses_a_broken_file_with_file_line_reason PROPERTIES
    FIXTURES_REQUIRED cal_rec
    PASS_REGULAR_EXPRESSION "broken\\.cal:4: offset_m is NaN.*calibration .*broken\\.cal not loaded")

  add_test(NAME calibrate_cli_firmware_process_loads_the_file_at_start
    COMMAND uwbnav firmware --recording ${cal_dir}/rec --cal ${cal_dir}/site.cal --console none --duration 1)
  set_tests_properties(calibrate_cli_firmware_process_loads_the_file_at_start PROPERTIES
    FIXTURES_REQUIRED cal_file LABELS realtime TIMEOUT 60
    PASS_REGULAR_EXPRESSION "calibration: .*site\\.cal \\(8 anchors x 3 tags.*stopped \\(duration\\)")
endif()
