# Shared part of the bare-metal Arm toolchain files (cortex-m4f.cmake,
# cortex-m7.cmake): arm-none-eabi GCC with picolibc (Debian packages
# gcc-arm-none-eabi, picolibc-arm-none-eabi, libstdc++-arm-none-eabi-picolibc).
# The including file sets UWBNAV_ARM_CPU_FLAGS (-mcpu/-mfpu/-mfloat-abi) first.
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(CMAKE_C_COMPILER arm-none-eabi-gcc)
set(CMAKE_CXX_COMPILER arm-none-eabi-g++)
set(CMAKE_ASM_COMPILER arm-none-eabi-gcc)
find_program(CMAKE_AR arm-none-eabi-ar)
find_program(CMAKE_RANLIB arm-none-eabi-ranlib)
find_program(CMAKE_OBJCOPY arm-none-eabi-objcopy)
find_program(CMAKE_SIZE arm-none-eabi-size)

# No OS to run a test executable: compiler checks build static libraries only.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# Firmware code generation: picolibc headers/libraries, no exceptions or RTTI
# anywhere in the image, one section per function/object so --gc-sections can
# drop what the image does not reach, and per object a .su and a .ci file
# (-fstack-usage, -fcallgraph-info=su) for the stack analysis (docs/footprint.md).
# _DEFAULT_SOURCE: the same libc feature set as the host, where g++ on glibc
# predefines _GNU_SOURCE (M_PI and friends stay visible under -std=c++17).
set(UWBNAV_ARM_COMMON_FLAGS "${UWBNAV_ARM_CPU_FLAGS} -specs=picolibc.specs -D_DEFAULT_SOURCE -ffunction-sections -fdata-sections -fstack-usage -fcallgraph-info=su")
set(CMAKE_C_FLAGS_INIT "${UWBNAV_ARM_COMMON_FLAGS}")
set(CMAKE_CXX_FLAGS_INIT "${UWBNAV_ARM_COMMON_FLAGS} -fno-exceptions -fno-rtti -fno-threadsafe-statics")
set(CMAKE_ASM_FLAGS_INIT "${UWBNAV_ARM_CPU_FLAGS}")
# The board's CMakeLists adds its linker script (-T) and map file; the startup
# code is the board's own (hal/mps2/startup.cpp), not picolibc's crt0.
set(CMAKE_EXE_LINKER_FLAGS_INIT "-nostartfiles -Wl,--gc-sections")

# Host programs (python, qemu) from the host; libraries and headers never.
set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
# Eigen is header-only and architecture independent: use the host's copy.
set(Eigen3_DIR /usr/share/eigen3/cmake CACHE PATH "Eigen3Config.cmake (header-only, from libeigen3-dev)")
