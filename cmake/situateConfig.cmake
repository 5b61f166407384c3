# situateConfig.cmake: the CMake package of situate's C/C++ skill ABI.
#
#   find_package(situate CONFIG REQUIRED)   # with situate_DIR="$(situate cmake-dir)", or
#                                           # CMAKE_PREFIX_PATH=<checkout>/cmake
#   situate_add_skill(my_skill MANIFEST my_skill.yaml SOURCES my_skill.c)
#
# The package is this directory and its ../include; the Python package ships both
# (`situate cmake-dir` prints where), a checkout has them at its top.
#
# Gives:
#   situate::situate   INTERFACE target: the include directory (situate.h, situate.hpp)
#   SITUATE_GENERATOR  the command that writes a manifest's structs: `situate-gen` when given
#                      (-DSITUATE_GEN=...) or built in this checkout, else `situate gen` of the
#                      `situate` program (-DSITUATE_PROGRAM=... or $SITUATE_PROGRAM, else found
#                      next to the Python package's scripts or on PATH). The release program
#                      alone is enough.
#   situate_add_skill(<target> MANIFEST <file> SOURCES <src>... [LANGUAGE C|CXX])
#       runs the generator (`c` or `cpp`, into the build directory) and builds <target> as a
#       shared library (only the entry symbol exported) that a robot file lists under `libraries:`.

get_filename_component(_situate_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
set(situate_INCLUDE_DIR "${_situate_root}/include")
set(situate_ABI_VERSION 2)

if(NOT TARGET situate::situate)
  add_library(situate::situate INTERFACE IMPORTED)
  set_target_properties(situate::situate PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${situate_INCLUDE_DIR}")
endif()

# The generator: situate-gen if asked for or built in this checkout (its target/), else the
# `situate` program, whose `situate gen` is the same generator.
if(NOT SITUATE_GEN AND NOT SITUATE_PROGRAM AND DEFINED ENV{SITUATE_PROGRAM})
  set(SITUATE_PROGRAM "$ENV{SITUATE_PROGRAM}")
endif()
if(NOT SITUATE_GEN AND NOT SITUATE_PROGRAM)
  set(_situate_hints "${_situate_root}/target/debug" "${_situate_root}/target/release")
  if(DEFINED ENV{CARGO_TARGET_DIR})
    list(PREPEND _situate_hints "$ENV{CARGO_TARGET_DIR}/debug" "$ENV{CARGO_TARGET_DIR}/release")
  endif()
  if(EXISTS "${_situate_root}/Cargo.toml")
    # A checkout: its own build of situate-gen, never one found elsewhere.
    find_program(SITUATE_GEN NAMES situate-gen HINTS ${_situate_hints} NO_DEFAULT_PATH)
  endif()
  if(NOT SITUATE_GEN)
    # The Python package's data is <prefix>/lib/pythonX.Y/site-packages/situate/_data: its
    # scripts are in <prefix>/bin (a virtualenv that is not activated, a --user install).
    find_program(SITUATE_PROGRAM NAMES situate
      HINTS "${_situate_root}/../../../../../bin" "${_situate_root}/../../../../../Scripts"
            ${_situate_hints})
  endif()
endif()
if(SITUATE_GEN)
  set(SITUATE_GENERATOR "${SITUATE_GEN}")
  set(_situate_gen_depends "${SITUATE_GEN}")
elseif(SITUATE_PROGRAM)
  set(SITUATE_GENERATOR "${SITUATE_PROGRAM}" -q gen)
  set(_situate_gen_depends "${SITUATE_PROGRAM}")
else()
  set(SITUATE_GENERATOR "")
endif()
if(SITUATE_GENERATOR AND NOT situate_FIND_QUIETLY)
  list(JOIN SITUATE_GENERATOR " " _situate_shown)
  message(STATUS "situate: C/C++ skill structs by `${_situate_shown}`")
endif()

function(situate_add_skill target)
  cmake_parse_arguments(ARG "" "MANIFEST;LANGUAGE" "SOURCES" ${ARGN})
  if(NOT ARG_MANIFEST OR NOT ARG_SOURCES)
    message(FATAL_ERROR "situate_add_skill(${target}): give MANIFEST <file> and SOURCES <file>...")
  endif()
  if(NOT SITUATE_GENERATOR)
    message(FATAL_ERROR "situate_add_skill(${target}): found no `situate` program to generate the "
                        "structs: put it on PATH (install the Python package, or build it with "
                        "cargo), or pass -DSITUATE_PROGRAM=/path/to/situate (or -DSITUATE_GEN=situate-gen)")
  endif()
  set(lang "${ARG_LANGUAGE}")
  if(NOT lang)
    set(lang C)
    foreach(src IN LISTS ARG_SOURCES)
      if(src MATCHES "\\.(cpp|cc|cxx|C)$")
        set(lang CXX)
      endif()
    endforeach()
  endif()
  if(lang STREQUAL "CXX")
    set(gen_lang cpp)
  elseif(lang STREQUAL "C")
    set(gen_lang c)
  else()
    message(FATAL_ERROR "situate_add_skill(${target}): LANGUAGE is C or CXX, got ${lang}")
  endif()
  get_filename_component(manifest "${ARG_MANIFEST}" ABSOLUTE)
  set(gen_dir "${CMAKE_CURRENT_BINARY_DIR}/${target}_situate")
  # Once now, to learn the generated file's name and fail early on a bad manifest.
  execute_process(
    COMMAND ${SITUATE_GENERATOR} ${gen_lang} "${manifest}" -o "${gen_dir}"
    OUTPUT_VARIABLE generated
    ERROR_VARIABLE gen_error
    RESULT_VARIABLE gen_result
    OUTPUT_STRIP_TRAILING_WHITESPACE)
  if(NOT gen_result EQUAL 0)
    message(FATAL_ERROR "situate_add_skill(${target}): ${gen_error}")
  endif()
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${manifest}")
  # And again at build time whenever the manifest or the generator changes.
  add_custom_command(
    OUTPUT "${generated}"
    COMMAND ${SITUATE_GENERATOR} ${gen_lang} "${manifest}" -o "${gen_dir}"
    DEPENDS "${manifest}" ${_situate_gen_depends}
    COMMENT "situate gen ${gen_lang} ${ARG_MANIFEST}"
    VERBATIM)
  add_library(${target} SHARED ${ARG_SOURCES} "${generated}")
  target_include_directories(${target} PRIVATE "${gen_dir}")
  target_link_libraries(${target} PRIVATE situate::situate)
  set_target_properties(${target} PROPERTIES
    C_VISIBILITY_PRESET hidden
    CXX_VISIBILITY_PRESET hidden
    VISIBILITY_INLINES_HIDDEN ON
    LINKER_LANGUAGE ${lang})
  if(lang STREQUAL "CXX")
    target_compile_features(${target} PRIVATE cxx_std_17)
  else()
    target_compile_features(${target} PRIVATE c_std_11)
  endif()
endfunction()
