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

install(TARGETS ${stage_targets} EXPORT vtexTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS vtex RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(FILES ${VTEX_SHARE_DIR}/vtex.bash DESTINATION ${CMAKE_INSTALL_DATADIR}/bash-completion/completions RENAME vtex)
install(FILES ${VTEX_SHARE_DIR}/vtex.1 DESTINATION ${CMAKE_INSTALL_MANDIR}/man1)
install(EXPORT vtexTargets NAMESPACE vtex:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/vtex)

get_property(config_dependencies GLOBAL PROPERTY VTEX_CONFIG_DEPENDENCIES)
list(REMOVE_DUPLICATES config_dependencies)
list(JOIN config_dependencies "\n" VTEX_CONFIG_EXTRA_DEPENDENCIES)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/vtexConfig.cmake.in
  ${PROJECT_BINARY_DIR}/vtexConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/vtex)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/vtexConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/vtexConfig.cmake ${PROJECT_BINARY_DIR}/vtexConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/vtex)
