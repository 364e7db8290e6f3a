# `cmake --install` puts the vtex program, the stage libraries, their headers and a package
# configuration in place, so that a C++ project can `find_package(vtex)` and link vtex::<stage>.
include(CMakePackageConfigHelpers)

get_property(stages GLOBAL PROPERTY VTEX_INSTALLED_STAGES)
set(stage_targets "")
foreach(stage IN LISTS stages)
  list(APPEND stage_targets vtex_${stage})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/${stage}/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
endforeach()
install(DIRECTORY ${PROJECT_BINARY_DIR}/generated/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# One export set per stage (vtex-<stage>Targets.cmake), so that find_package(vtex COMPONENTS
# octree) defines vtex::octree and what it links (vtex::core) and looks for their packages only,
# not CGAL, OpenMesh, Embree or tinygltf. The table the config file reads: per stage, the vtex
# stages it links (from its link libraries) and the packages it needs (vtex_config_dependency).
set(VTEX_COMPONENT_TABLE "")
foreach(stage IN LISTS stages)
  install(TARGETS vtex_${stage} EXPORT vtex-${stage}Targets
          ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
          LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
          INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  install(EXPORT vtex-${stage}Targets NAMESPACE vtex:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/vtex)
  get_target_property(links vtex_${stage} LINK_LIBRARIES)
  set(linked "")
  foreach(link IN LISTS links)
    if(link MATCHES "^vtex::([a-z]+)$" AND NOT CMAKE_MATCH_1 STREQUAL stage)
      list(APPEND linked ${CMAKE_MATCH_1})
    endif()
  endforeach()
  get_property(packages GLOBAL PROPERTY VTEX_CONFIG_DEPENDENCIES_${stage})
  list(REMOVE_DUPLICATES packages)
  list(JOIN packages "|" packages)
  string(APPEND VTEX_COMPONENT_TABLE "set(_vtex_links_${stage} \"${linked}\")\nset(_vtex_packages_${stage} \"${packages}\")\n")
endforeach()
set(VTEX_COMPONENTS "${stages}")
install(TARGETS vtex RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${VTEX_SHARE_DIR}/vtex.bash DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME vtex)
install(FILES ${VTEX_SHARE_DIR}/vtex.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/vtexConfig.cmake.in
  ${PROJECT_BINARY_DIR}/vtexConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/vtex)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vtexConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vtexConfig.cmake ${PROJECT_BINARY_DIR}/vtexConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/vtex)
