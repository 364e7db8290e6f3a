# Shared settings for every vtex target.

add_library(vtex_warnings INTERFACE)
target_compile_options(vtex_warnings INTERFACE -Wall -Wextra -Wpedantic)
if(VTEX_SANITIZE)
  target_compile_options(vtex_warnings INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer
                                                 -fno-sanitize-recover=undefined)
  target_link_options(vtex_warnings INTERFACE -fsanitize=address,undefined)
endif()

# vtex_stage_library(<stage> SOURCES ... [PUBLIC_DEPS ...] [PRIVATE_DEPS ...])
# Declares the static library vtex_<stage> (alias vtex::<stage>) whose public headers live in
# <stage>/include/vtex/<stage>/, and registers it for installation and export.
function(vtex_stage_library stage)
  cmake_parse_arguments(ARG "" "" "SOURCES;PUBLIC_DEPS;PRIVATE_DEPS" ${ARGN})
  add_library(vtex_${stage} STATIC ${ARG_SOURCES})
  add_library(vtex::${stage} ALIAS vtex_${stage})
  set_target_properties(vtex_${stage} PROPERTIES EXPORT_NAME ${stage} OUTPUT_NAME vtex_${stage})
  target_include_directories(vtex_${stage} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  target_link_libraries(vtex_${stage} PUBLIC ${ARG_PUBLIC_DEPS} PRIVATE ${ARG_PRIVATE_DEPS}
                        $<BUILD_INTERFACE:vtex_warnings>)
  target_compile_features(vtex_${stage} PUBLIC cxx_std_20)
  if(VTEX_SANITIZE)
    # Instrumented static code needs the sanitizer runtimes wherever it is linked, installed too.
    target_link_options(vtex_${stage} INTERFACE -fsanitize=address,undefined)
  endif()
  set_property(GLOBAL APPEND PROPERTY VTEX_INSTALLED_STAGES ${stage})
endfunction()

# vtex_config_dependency(<package> [args...]): a package the installed static library of the
# calling stage (the folder's name: ingest/, render/, …) needs at link time; vtexConfig.cmake
# calls find_dependency() for it when that stage is among the components asked for.
function(vtex_config_dependency)
  get_filename_component(stage ${CMAKE_CURRENT_SOURCE_DIR} NAME)
  string(JOIN " " args ${ARGN})
  set_property(GLOBAL APPEND PROPERTY VTEX_CONFIG_DEPENDENCIES_${stage} "${args}")
endfunction()
