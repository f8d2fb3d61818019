# Cross check of the Cortex-M4F firmware image (issue 4): builds the MPS2-AN386
# image (hal/mps2) with arm-none-eabi, runs it under qemu-system-arm, and
# compares its digest with `uwbnav replay` of the same recording on the host
# (hal/mps2/check_replay.py); checks the image rules (no heap, no exceptions,
# no soft-double in the estimator hot path: hal/mps2/image_analysis.py) and
# that the check catches a canary that breaks them. The tests share one build
# tree (RESOURCE_LOCK) and run after cross_m4f_build_image (fixture).
# Registered in native host builds only; when the cross tools are missing the
# test reports "skipped" with the reason.
if(CMAKE_CROSSCOMPILING)
  return()
endif()

find_program(UWBNAV_ARM_GXX arm-none-eabi-g++)
find_program(UWBNAV_QEMU_SYSTEM_ARM qemu-system-arm)
set(UWBNAV_CROSS_M4F_DIR ${PROJECT_BINARY_DIR}/cross-m4f CACHE PATH "Build tree of the MPS2 image used by cross_m4f_* tests")

set(skip_reason "")
if(NOT UWBNAV_ARM_GXX)
  set(skip_reason "arm-none-eabi-g++ not found (scripts/bootstrap.sh installs gcc-arm-none-eabi)")
elseif(NOT EXISTS /usr/lib/picolibc/arm-none-eabi/picolibc.specs)
  set(skip_reason "picolibc for arm-none-eabi not found (package picolibc-arm-none-eabi)")
elseif(NOT UWBNAV_QEMU_SYSTEM_ARM)
  set(skip_reason "qemu-system-arm not found (package qemu-system-arm)")
elseif(NOT EXISTS /usr/bin/python3)
  set(skip_reason "/usr/bin/python3 not found")
elseif("${CMAKE_CXX_FLAGS}" MATCHES "-fsanitize")
  set(skip_reason "sanitizer build: the image check runs in the unsanitized host presets")
endif()

if(skip_reason)
  add_test(NAME cross_m4f_replay_matches_host
    COMMAND /bin/sh -c "echo 'cross_m4f_replay_matches_host skipped: ${skip_reason}'; exit 77")
  set_tests_properties(cross_m4f_replay_matches_host PROPERTIES SKIP_RETURN_CODE 77)
  return()
endif()

add_test(NAME cross_m4f_build_image
  COMMAND ${CMAKE_COMMAND} -DSOURCE=${PROJECT_SOURCE_DIR} -DBINARY=${UWBNAV_CROSS_M4F_DIR}
    -DUWBNAV=$<TARGET_FILE:uwbnav> -DGENERATOR=${CMAKE_GENERATOR}
    -P ${PROJECT_SOURCE_DIR}/hal/mps2/build_image.cmake)
set_tests_properties(cross_m4f_build_image PROPERTIES FIXTURES_SETUP cross_m4f_image TIMEOUT 1800
  RESOURCE_LOCK cross_m4f_tree)

add_test(NAME cross_m4f_replay_matches_host
  COMMAND /usr/bin/python3 ${PROJECT_SOURCE_DIR}/hal/mps2/check_replay.py
    --qemu ${UWBNAV_QEMU_SYSTEM_ARM} --machine mps2-an386
    --image ${UWBNAV_CROSS_M4F_DIR}/hal/mps2/uwbnav_mps2.elf
    --recording ${UWBNAV_CROSS_M4F_DIR}/hal/mps2/recording
    --uwbnav $<TARGET_FILE:uwbnav>
    --out ${CMAKE_CURRENT_BINARY_DIR}/cross_m4f)
set_tests_properties(cross_m4f_replay_matches_host PROPERTIES FIXTURES_REQUIRED cross_m4f_image TIMEOUT 900
  RESOURCE_LOCK cross_m4f_tree)

add_test(NAME cross_m4f_image_rules
  COMMAND ${CMAKE_COMMAND} --build ${UWBNAV_CROSS_M4F_DIR} --target uwbnav_mps2_check)
set_tests_properties(cross_m4f_image_rules PROPERTIES FIXTURES_REQUIRED cross_m4f_image TIMEOUT 300
  RESOURCE_LOCK cross_m4f_tree)

add_test(NAME cross_m4f_image_rules_catch_heap_and_soft_double
  COMMAND ${CMAKE_COMMAND} -DSOURCE=${PROJECT_SOURCE_DIR} -DBINARY=${UWBNAV_CROSS_M4F_DIR}
    -P ${PROJECT_SOURCE_DIR}/hal/mps2/check_canary.cmake)
set_tests_properties(cross_m4f_image_rules_catch_heap_and_soft_double PROPERTIES
  FIXTURES_REQUIRED cross_m4f_image TIMEOUT 600 RESOURCE_LOCK cross_m4f_tree)
