# docs/dataset-format.md must hold the shared format v1 spec unchanged: every
# line of the shared copy, in the same order, none changed or dropped. The
# project may add lines between them (its documented extensions of format v1,
# e.g. gnss.csv), which readers that predate them ignore.
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
file(READ "${SHARED_SPEC}" shared)
file(READ "${PROJECT_SPEC}" project)
# Greedy in-order match of whole lines; strings only (the text has ';', never a CMake list).
set(rest "\n${project}\n")
string(LENGTH "${shared}" n)
set(pos 0)
set(line_no 0)
while(pos LESS n)
  string(SUBSTRING "${shared}" ${pos} -1 tail)
  string(FIND "${tail}" "\n" nl)
  if(nl EQUAL -1)
    set(line "${tail}")
    set(pos ${n})
  else()
    string(SUBSTRING "${tail}" 0 ${nl} line)
    math(EXPR pos "${pos} + ${nl} + 1")
  endif()
  math(EXPR line_no "${line_no} + 1")
  string(FIND "${rest}" "\n${line}\n" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${PROJECT_SPEC} lacks line ${line_no} of ${SHARED_SPEC} (or has it out of order): "
                        "'${line}'. The format v1 spec changed: update docs/dataset-format.md and the "
                        "reader/writer in tools/dataset/")
  endif()
  string(LENGTH "${line}" len)
  math(EXPR next "${at} + ${len} + 1")
  string(SUBSTRING "${rest}" ${next} -1 rest)
endwhile()
message(STATUS "docs/dataset-format.md holds ${SHARED_SPEC} (${line_no} lines) in order")
