# CAN proof with tools nobody here wrote: python3-can reads the firmware's
# candump log, python3-canmatrix decodes it with docs/uwbnav.dbc, and
# tests/scripts/can_decode.py checks CRCs, alive counters and positions
# against estimates.csv (docs/can.md "Verification").
set(UWBNAV_PYTHON3 /usr/bin/python3)
set(can_decode_py ${CMAKE_CURRENT_SOURCE_DIR}/scripts/can_decode.py)
set(can_dbc ${PROJECT_SOURCE_DIR}/docs/uwbnav.dbc)

if(TARGET uwbnav_tests_can)
  # 1. A log + estimates.csv written by CanPublisher through the candump tee (no CLI needed).
  set(can_fixture_dir ${PROJECT_BINARY_DIR}/tests/can_fixture)
  add_test(NAME can_fixture_log_written
    COMMAND uwbnav_tests_can --gtest_filter=CanFixture.*)
  set_tests_properties(can_fixture_log_written PROPERTIES
    ENVIRONMENT "UWBNAV_CAN_FIXTURE_DIR=${can_fixture_dir}"
    FIXTURES_SETUP can_fixture_log)
  add_test(NAME can_decode_fixture_log_with_python_can_and_canmatrix
    COMMAND ${UWBNAV_PYTHON3} ${can_decode_py} --dbc ${can_dbc}
      --log ${can_fixture_dir}/can.log --estimates ${can_fixture_dir}/estimates.csv --min-positions 500
      --min-coop-groups 48 --coop-tag-at-origin)
  set_tests_properties(can_decode_fixture_log_with_python_can_and_canmatrix PROPERTIES
    FIXTURES_REQUIRED can_fixture_log)
  # Negative controls: the checker must catch a flipped bit, a missing frame, a moved estimate.
  foreach(mutation crc counter position)
    add_test(NAME can_decode_detects_${mutation}_corruption
      COMMAND ${UWBNAV_PYTHON3} ${can_decode_py} --dbc ${can_dbc} --mutate ${mutation}
        --log ${can_fixture_dir}/can.log --estimates ${can_fixture_dir}/estimates.csv)
    set_tests_properties(can_decode_detects_${mutation}_corruption PROPERTIES
      FIXTURES_REQUIRED can_fixture_log
      PASS_REGULAR_EXPRESSION "can_decode: [0-9]+ check\\(s\\) failed")
  endforeach()
endif()

if(TARGET uwbnav)
  # 2. End to end: simulate, replay through the firmware (host board tees CAN into
  # OUT/can.log), decode the firmware's own log.
  set(can_e2e_dir ${PROJECT_BINARY_DIR}/tests/can_e2e)
  add_test(NAME can_e2e_sim_parking_nlos
    COMMAND uwbnav sim parking_nlos --out ${can_e2e_dir}/sim --seed 7)
  set_tests_properties(can_e2e_sim_parking_nlos PROPERTIES FIXTURES_SETUP can_e2e_sim)
  add_test(NAME can_e2e_replay
    COMMAND uwbnav replay ${can_e2e_dir}/sim --out ${can_e2e_dir}/replay)
  set_tests_properties(can_e2e_replay PROPERTIES
    FIXTURES_REQUIRED can_e2e_sim FIXTURES_SETUP can_e2e_replay)
  add_test(NAME can_decode_firmware_replay_log_with_python_can_and_canmatrix
    COMMAND ${UWBNAV_PYTHON3} ${can_decode_py} --dbc ${can_dbc}
      --log ${can_e2e_dir}/replay/can.log --estimates ${can_e2e_dir}/replay/estimates.csv --min-positions 100)
  set_tests_properties(can_decode_firmware_replay_log_with_python_can_and_canmatrix PROPERTIES
    FIXTURES_REQUIRED can_e2e_replay TIMEOUT 900)
endif()
