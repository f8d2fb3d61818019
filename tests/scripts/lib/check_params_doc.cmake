# Fails when docs/parameters.md differs from `uwbnav params --markdown` (regenerate with
# build/host/bin/uwbnav params --markdown > docs/parameters.md).
execute_process(COMMAND ${UWBNAV} params --markdown OUTPUT_VARIABLE generated RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "uwbnav params failed (${rc})")
endif()
file(READ ${DOC} committed)
if(NOT generated STREQUAL committed)
  message(FATAL_ERROR "docs/parameters.md is stale: regenerate it with `uwbnav params --markdown > docs/parameters.md`")
endif()
