# GTest package config for GoogleTest built from source in this build tree
# (toolchain/gtest_from_source.cmake defines the GTest:: targets).
foreach(t gtest gtest_main gmock gmock_main)
  if(NOT TARGET GTest::${t})
    set(GTest_FOUND FALSE)
    set(GTest_NOT_FOUND_MESSAGE "GTest::${t} missing: include toolchain/gtest_from_source.cmake after project()")
    return()
  endif()
endforeach()
set(GTest_FOUND TRUE)
