# CMake toolchain file: aarch64 Linux ECUs (Debian g++-aarch64-linux-gnu). Test
# executables run on the build machine under qemu-aarch64 (qemu-user) through
# CMAKE_CROSSCOMPILING_EMULATOR, so gtest discovery and ctest work unchanged.
# GoogleTest is built from Debian's sources (package googletest) by
# toolchain/gtest_from_source.cmake; libsvm comes from libsvm-dev:arm64 (multiarch).
set(CMAKE_SYSTEM_NAME Linux)
set(CMAKE_SYSTEM_PROCESSOR aarch64)

set(CMAKE_C_COMPILER aarch64-linux-gnu-gcc)
set(CMAKE_CXX_COMPILER aarch64-linux-gnu-g++)
set(CMAKE_LIBRARY_ARCHITECTURE aarch64-linux-gnu)

set(UWBNAV_AARCH64_SYSROOT /usr/aarch64-linux-gnu)
set(CMAKE_CROSSCOMPILING_EMULATOR qemu-aarch64;-L;${UWBNAV_AARCH64_SYSROOT})

# Libraries: the cross libc in /usr/aarch64-linux-gnu and Debian's arm64
# multiarch packages in /usr/lib/aarch64-linux-gnu; never the host's x86-64 ones.
set(CMAKE_FIND_ROOT_PATH ${UWBNAV_AARCH64_SYSROOT} /)
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# Static libsvm (libsvm-dev:arm64): binaries then need only the cross libc at run time.
set(LIBSVM_LIBRARY /usr/lib/aarch64-linux-gnu/libsvm.a CACHE FILEPATH "libsvm for aarch64 (static)")
# zlib (.csv.gz recordings) static as well: qemu-aarch64 -L only sees the sysroot, not /usr/lib/aarch64-linux-gnu.
set(ZLIB_LIBRARY /usr/lib/aarch64-linux-gnu/libz.a CACHE FILEPATH "zlib for aarch64 (static, zlib1g-dev:arm64)")
set(ZLIB_INCLUDE_DIR /usr/include CACHE PATH "zlib.h (architecture-independent)")

# Header-only Eigen from the host (architecture independent).
set(Eigen3_DIR /usr/share/eigen3/cmake CACHE PATH "Eigen3Config.cmake (header-only, from libeigen3-dev)")
# GoogleTest compiled for the target from /usr/src/googletest right after project().
set(CMAKE_PROJECT_uwbnav_INCLUDE ${CMAKE_CURRENT_LIST_DIR}/gtest_from_source.cmake)
set(GTest_DIR ${CMAKE_CURRENT_LIST_DIR}/gtest_from_source CACHE PATH "GTestConfig.cmake for the GoogleTest built from source")
