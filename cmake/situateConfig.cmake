# situateConfig.cmake: the CMake package of situate's C/C++ skill ABI.
#
#   find_package(situate CONFIG REQUIRED)   # with CMAKE_PREFIX_PATH=<repo>/cmake or situate_DIR=<repo>/cmake
#   situate_add_skill(my_skill MANIFEST my_skill.yaml SOURCES my_skill.c)
#
# Gives:
#   situate::situate   INTERFACE target: the include directory (situate.h, situate.hpp)
#   SITUATE_GEN        the generator (`situate-gen`); set it (-DSITUATE_GEN=...) or let it be found
#   situate_add_skill(<target> MANIFEST <file> SOURCES <src>... [LANGUAGE C|CXX])
#       runs `situate-gen c|cpp <file>` into the build directory and builds <target> as a
#       shared library (only the entry symbol exported) that a robot file lists under `libraries:`.

get_filename_component(_situate_root "${CMAKE_CURRENT_LIST_DIR}/.." ABSOLUTE)
set(situate_INCLUDE_DIR "${_situate_root}/include")
set(situate_ABI_VERSION 1)

if(NOT TARGET situate::situate)
  add_library(situate::situate INTERFACE IMPORTED)
  set_target_properties(situate::situate PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${situate_INCLUDE_DIR}")
endif()

if(NOT SITUATE_GEN)
  set(_situate_hints "${_situate_root}/target/debug" "${_situate_root}/target/release")
  if(DEFINED ENV{CARGO_TARGET_DIR})
    list(PREPEND _situate_hints "$ENV{CARGO_TARGET_DIR}/debug" "$ENV{CARGO_TARGET_DIR}/release")
  endif()
  find_program(SITUATE_GEN NAMES situate-gen HINTS ${_situate_hints})
endif()

function(situate_add_skill target)
  cmake_parse_arguments(ARG "" "MANIFEST;LANGUAGE" "SOURCES" ${ARGN})
  if(NOT ARG_MANIFEST OR NOT ARG_SOURCES)
    message(FATAL_ERROR "situate_add_skill(${target}): give MANIFEST <file> and SOURCES <file>...")
  endif()
  if(NOT SITUATE_GEN)
    message(FATAL_ERROR "situate_add_skill(${target}): situate-gen not found; build it "
                        "(cargo build -p situate_cabi) or pass -DSITUATE_GEN=/path/to/situate-gen")
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
    COMMAND "${SITUATE_GEN}" ${gen_lang} "${manifest}" -o "${gen_dir}"
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
    COMMAND "${SITUATE_GEN}" ${gen_lang} "${manifest}" -o "${gen_dir}"
    DEPENDS "${manifest}" "${SITUATE_GEN}"
    COMMENT "situate-gen ${gen_lang} ${ARG_MANIFEST}"
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
