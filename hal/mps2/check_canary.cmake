# Self-test of the image rule check: builds uwbnav_mps2_canary (the image plus
# rule_canary.cpp, which calls malloc and computes in double) and requires
# image_analysis.py check to fail and name both violations.
# cmake -DBINARY=<image build tree> -DSOURCE=<repo> -P hal/mps2/check_canary.cmake
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} --target uwbnav_mps2_canary RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building uwbnav_mps2_canary failed (${rc})")
endif()
set(dir ${BINARY}/hal/mps2)
execute_process(
  COMMAND /usr/bin/python3 ${SOURCE}/hal/mps2/image_analysis.py check
    --elf ${dir}/uwbnav_mps2_canary.elf --map ${dir}/uwbnav_mps2_canary.map
    --estimator-lib rule_canary.cpp.obj --roots _ZN6uwbnav4mps26canary8hot_path
    --callgraph-dir ${BINARY}
  RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
message("${out}${err}")
if(rc EQUAL 0)
  message(FATAL_ERROR "image_analysis.py check passed an image that calls malloc and uses double")
endif()
string(REGEX MATCH "heap: malloc is linked[^\n]*" heap_line "${err}")
string(FIND "${heap_line}" "uwbnav::mps2::canary::hot_path(float)" at)
if(at EQUAL -1)
  message(FATAL_ERROR "image_analysis.py check did not name the canary as a malloc caller")
endif()
string(FIND "${err}" "soft-double in the estimator hot path: uwbnav::mps2::canary::hot_path(float) calls __aeabi_f2d" at)
if(at EQUAL -1)
  message(FATAL_ERROR "image_analysis.py check did not report the canary's float->double conversion")
endif()
