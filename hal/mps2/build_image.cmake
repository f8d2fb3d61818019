# Configures (once) and builds the MPS2 firmware image in BINARY with the
# Cortex-M4F toolchain, using the host tool UWBNAV to simulate the recording.
# cmake -DSOURCE=<repo> -DBINARY=<dir> -DUWBNAV=<host uwbnav> [-DTOOLCHAIN=cortex-m4f]
#       [-DGENERATOR=Ninja] [-DJOBS=2] -P hal/mps2/build_image.cmake
foreach(v SOURCE BINARY UWBNAV)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "build_image.cmake: -D${v}=... is required")
  endif()
endforeach()
if(NOT DEFINED TOOLCHAIN)
  set(TOOLCHAIN cortex-m4f)
endif()
if(NOT DEFINED GENERATOR)
  set(GENERATOR Ninja)
endif()
if(NOT DEFINED JOBS)
  set(JOBS 2)
endif()

execute_process(
  COMMAND ${CMAKE_COMMAND} -S ${SOURCE} -B ${BINARY} -G ${GENERATOR}
    --toolchain ${SOURCE}/toolchain/${TOOLCHAIN}.cmake
    -DCMAKE_BUILD_TYPE=Release -DUWBNAV_BOARD=mps2
    -DUWBNAV_BUILD_HOST=OFF -DUWBNAV_BUILD_TESTS=OFF -DUWBNAV_BUILD_BENCHMARKS=OFF
    -DUWBNAV_HOST_UWBNAV=${UWBNAV}
  RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "configuring the ${TOOLCHAIN} image in ${BINARY} failed (${rc})")
endif()
execute_process(COMMAND ${CMAKE_COMMAND} --build ${BINARY} --target uwbnav_mps2 -j ${JOBS} RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "building the ${TOOLCHAIN} image in ${BINARY} failed (${rc})")
endif()
