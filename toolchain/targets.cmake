# uwbnav_glob_library(NAME GLOBS...): a static library of the files the globs
# match; components add source files without editing CMake.
function(uwbnav_glob_library name)
  file(GLOB srcs CONFIGURE_DEPENDS ${ARGN})
  if(NOT srcs)
    set(empty ${CMAKE_CURRENT_BINARY_DIR}/${name}_nosources.cpp)
    file(WRITE ${empty} "// ${name}: component without sources in this build\n")
    set(srcs ${empty})
  endif()
  add_library(${name} STATIC ${srcs})
  target_include_directories(${name} PUBLIC ${PROJECT_SOURCE_DIR})
  target_link_libraries(${name} PRIVATE uwbnav_warnings)
endfunction()
