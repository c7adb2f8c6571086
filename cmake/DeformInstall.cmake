# install() rules and the exported package so that an engine can do
#   find_package(libdeform CONFIG REQUIRED)
#   target_link_libraries(app PRIVATE deform::deform)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(DEFORM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/libdeform)

install(TARGETS deform EXPORT libdeformTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/libdeform/include/deform DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
if(TARGET deform_import)
  install(TARGETS deform_import EXPORT libdeformTargets
    ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
    LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
    RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()
if(TARGET deform_cli)
  install(TARGETS deform_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

install(EXPORT libdeformTargets NAMESPACE deform:: DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/libdeformConfig.cmake.in
  ${PROJECT_BINARY_DIR}/libdeformConfig.cmake INSTALL_DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/libdeformConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/libdeformConfig.cmake ${PROJECT_BINARY_DIR}/libdeformConfigVersion.cmake
  DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
