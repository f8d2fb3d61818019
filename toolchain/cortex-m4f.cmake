# CMake toolchain file: Cortex-M4F (ARMv7E-M, single-precision FPv4 FPU, hard-float
# ABI), arm-none-eabi GCC + picolibc. Used by the `cortex-m4f` preset with
# UWBNAV_BOARD=mps2 (image for qemu-system-arm -M mps2-an386).
set(UWBNAV_ARM_CPU_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard")
include(${CMAKE_CURRENT_LIST_DIR}/arm-none-eabi.cmake)
