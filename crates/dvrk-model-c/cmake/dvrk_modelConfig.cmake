# find_package(dvrk_model) for the dvrk-model C library, as crates/dvrk-model-c/install.sh
# lays it out under a prefix (this file in <prefix>/lib/cmake/dvrk_model). It defines
#   dvrk_model::dvrk_model         the shared library (libdvrk_model_c.so)
#   dvrk_model::dvrk_model_static  the static library, with the system libraries the Rust
#                                  standard library inside it needs
# both with <prefix>/include (dvrk_model.h, dvrk_model.hpp) as include directory:
#   find_package(dvrk_model 0.1 REQUIRED)
#   target_link_libraries(my_controller PRIVATE dvrk_model::dvrk_model)
# The prefix is found from this file's place, so an installed tree may be moved.
get_filename_component(_dvrk_model_prefix "${CMAKE_CURRENT_LIST_DIR}/../../.." ABSOLUTE)

if(APPLE)
  set(_dvrk_model_shared "${_dvrk_model_prefix}/lib/libdvrk_model_c.dylib")
else()
  set(_dvrk_model_shared "${_dvrk_model_prefix}/lib/libdvrk_model_c.so")
endif()
set(_dvrk_model_static "${_dvrk_model_prefix}/lib/libdvrk_model_c.a")
set(_dvrk_model_include "${_dvrk_model_prefix}/include")

foreach(_dvrk_model_file "${_dvrk_model_shared}" "${_dvrk_model_static}"
        "${_dvrk_model_include}/dvrk_model.h")
  if(NOT EXISTS "${_dvrk_model_file}")
    set(dvrk_model_FOUND FALSE)
    set(dvrk_model_NOT_FOUND_MESSAGE "${_dvrk_model_file} is missing")
    return()
  endif()
endforeach()

if(NOT TARGET dvrk_model::dvrk_model)
  add_library(dvrk_model::dvrk_model SHARED IMPORTED)
  set_target_properties(dvrk_model::dvrk_model PROPERTIES
    IMPORTED_LOCATION "${_dvrk_model_shared}"
    INTERFACE_INCLUDE_DIRECTORIES "${_dvrk_model_include}")
endif()
if(NOT TARGET dvrk_model::dvrk_model_static)
  add_library(dvrk_model::dvrk_model_static STATIC IMPORTED)
  # What `rustc --print native-static-libs` names for the static library on Linux (the
  # same list as Libs.private in dvrk_model.pc).
  set_target_properties(dvrk_model::dvrk_model_static PROPERTIES
    IMPORTED_LOCATION "${_dvrk_model_static}"
    INTERFACE_INCLUDE_DIRECTORIES "${_dvrk_model_include}"
    INTERFACE_LINK_LIBRARIES "gcc_s;util;rt;pthread;m;dl;c")
endif()
set(dvrk_model_INCLUDE_DIRS "${_dvrk_model_include}")
set(dvrk_model_LIBRARIES dvrk_model::dvrk_model)
