# Runs the fast family subset on two cells and checks the printed tables; then
# writes one family drive as a recording and replays it. Inputs: UWBNAV, WORK.
execute_process(COMMAND ${UWBNAV} eval family --fast --cells ground_los,trolley3 --markdown --jobs 2
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "uwbnav eval family failed (${rc}):\n${out}\n${err}")
endif()
foreach(pattern "| ground_los " "| trolley3 " "| all cells " "TUNING set" "reporting 1000-1999"
                "NEES mean" "NIS mean" "inflate/h" "re-anchor/h" "re-align/h" "fallback" "wall time")
  string(FIND "${out}" "${pattern}" pos)
  if(pos EQUAL -1)
    message(FATAL_ERROR "eval family output lacks '${pattern}':\n${out}")
  endif()
endforeach()
execute_process(COMMAND ${UWBNAV} eval family --cells nope RESULT_VARIABLE rc OUTPUT_QUIET ERROR_VARIABLE err)
if(NOT rc EQUAL 2 OR NOT err MATCHES "unknown cell 'nope'")
  message(FATAL_ERROR "an unknown cell must be a usage error (2), got ${rc}: ${err}")
endif()

file(REMOVE_RECURSE ${WORK})
execute_process(COMMAND ${UWBNAV} sim family:trolley3:1000 --out ${WORK}/rec RESULT_VARIABLE rc OUTPUT_VARIABLE out
  ERROR_VARIABLE err)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "uwbnav sim family:trolley3:1000 failed (${rc}): ${err}")
endif()
file(READ ${WORK}/rec/meta.ini meta)
if(NOT meta MATCHES "sim_family = trolley3:1000")
  message(FATAL_ERROR "meta.ini does not name the family drive:\n${meta}")
endif()
execute_process(COMMAND ${UWBNAV} replay ${WORK}/rec --out ${WORK}/out RESULT_VARIABLE rc OUTPUT_VARIABLE out
  ERROR_VARIABLE err)
if(NOT rc EQUAL 0 OR NOT EXISTS ${WORK}/out/estimates.csv)
  message(FATAL_ERROR "replaying the family recording failed (${rc}): ${out} ${err}")
endif()
execute_process(COMMAND ${UWBNAV} sim --list RESULT_VARIABLE rc OUTPUT_VARIABLE out)
if(NOT out MATCHES "family:ground_blocked" OR NOT out MATCHES "drone_indoor")
  message(FATAL_ERROR "uwbnav sim --list lacks the family cells or the new preset:\n${out}")
endif()
