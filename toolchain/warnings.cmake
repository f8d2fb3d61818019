# Project-wide warning policy: warnings are errors everywhere we own the code.
add_library(uwbnav_warnings INTERFACE)
target_compile_options(uwbnav_warnings INTERFACE
  -Wall -Wextra -Werror -Wshadow -Wdouble-promotion -Wnon-virtual-dtor
  -Wcast-align -Wformat=2 -Wimplicit-fallthrough)

# Firmware-grade code (estimator/, firmware/): no exceptions, no RTTI.
add_library(uwbnav_firmware_flags INTERFACE)
target_compile_options(uwbnav_firmware_flags INTERFACE
  $<$<COMPILE_LANGUAGE:CXX>:-fno-exceptions -fno-rtti>)
target_compile_definitions(uwbnav_firmware_flags INTERFACE EIGEN_NO_MALLOC EIGEN_MPL2_ONLY)
