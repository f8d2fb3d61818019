# CMake toolchain file: Cortex-M7 (ARMv7E-M, double-precision FPv5 FPU, hard-float
# ABI), arm-none-eabi GCC + picolibc. Used by the `cortex-m7` preset with
# UWBNAV_BOARD=mps2 (image for qemu-system-arm -M mps2-an500).
set(UWBNAV_ARM_CPU_FLAGS "-mcpu=cortex-m7 -mthumb -mfpu=fpv5-d16 -mfloat-abi=hard")
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
