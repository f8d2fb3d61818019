# Builds GoogleTest/GoogleMock for the target from Debian's sources (package
# googletest, /usr/src/googletest) when cross-compiling, with the target names of
# the installed package (GTest::gtest, GTest::gtest_main, GTest::gmock,
# GTest::gmock_main; googletest 1.12 defines these aliases itself). Included
# right after project() by the aarch64 toolchain (CMAKE_PROJECT_uwbnav_INCLUDE);
# tests/CMakeLists.txt's find_package(GTest) then finds
# toolchain/gtest_from_source/GTestConfig.cmake, which only checks the targets.
set(UWBNAV_GOOGLETEST_SRC /usr/src/googletest CACHE PATH "GoogleTest sources (Debian package googletest)")
if(NOT EXISTS ${UWBNAV_GOOGLETEST_SRC}/CMakeLists.txt)
  message(FATAL_ERROR "GoogleTest sources not found in ${UWBNAV_GOOGLETEST_SRC}: install the Debian package googletest (scripts/bootstrap.sh)")
endif()
set(INSTALL_GTEST OFF CACHE BOOL "" FORCE)
set(BUILD_GMOCK ON CACHE BOOL "" FORCE)
add_subdirectory(${UWBNAV_GOOGLETEST_SRC} ${CMAKE_BINARY_DIR}/_googletest EXCLUDE_FROM_ALL SYSTEM)
foreach(t gtest gtest_main gmock gmock_main)
  if(NOT TARGET GTest::${t})
    add_library(GTest::${t} ALIAS ${t})
  endif()
endforeach()
