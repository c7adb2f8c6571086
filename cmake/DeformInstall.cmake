# install() rules and the exported package, so that an engine can do
#   find_package(libdeform CONFIG REQUIRED)                      # runtime, offline, io, character, extras
#   target_link_libraries(engine PRIVATE deform::runtime)        # or any layer, or deform::deform for all of them
#   target_link_libraries(tool PRIVATE deform::c)                 # the C API (deform/c/deform.h)
#   find_package(libdeform CONFIG REQUIRED COMPONENTS import)    # also deform::import: only then is Assimp looked for
#   find_package(libdeform CONFIG REQUIRED COMPONENTS gpu)       # also deform::gpu (OpenGL 4.3 compute lattices)
#   find_package(libdeform CONFIG REQUIRED COMPONENTS simplify)  # also deform::simplify (meshoptimizer is looked for)
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(DEFORM_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/libdeform)
set(deform_install_args
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

install(TARGETS deform_runtime deform_offline deform_io deform_character deform_extras deform_c deform
  EXPORT libdeformTargets ${deform_install_args})
install(EXPORT libdeformTargets NAMESPACE deform:: DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/libdeform/include/deform DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  PATTERN "import" EXCLUDE PATTERN "gpu" EXCLUDE PATTERN "simplify" EXCLUDE)
# deform-c.pc: the C API for a build without CMake: cc app.c $(pkg-config --cflags --libs deform-c). Relocatable
# (paths from the .pc file's own folder), so an install with --prefix anywhere works. A static build lists every
# layer's archive, in link order, and the C++ runtime; a shared one, libdeform_c alone.
set(deform_pc_libs "-ldeform_c")
set(deform_pc_private "-ldeform_extras -ldeform_character -ldeform_io -ldeform_offline -ldeform_runtime -pthread")
if(TARGET deform_import)  # deform_character_import's object needs the import layer and Assimp (shared on Debian)
  set(deform_pc_private "-ldeform_import ${deform_pc_private} -lassimp")
endif()
if(NOT BUILD_SHARED_LIBS)
  get_property(deform_cxx_runtime GLOBAL PROPERTY DEFORM_CXX_RUNTIME)
  list(TRANSFORM deform_cxx_runtime PREPEND "-l")
  list(JOIN deform_cxx_runtime " " deform_cxx_runtime)
  string(APPEND deform_pc_libs " ${deform_pc_private} ${deform_cxx_runtime}")
  set(deform_pc_private "")
endif()
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(deform_pc_prefix "${CMAKE_INSTALL_PREFIX}")
else()
  file(RELATIVE_PATH deform_pc_up "/root/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/root")
  set(deform_pc_prefix "\${pcfiledir}/${deform_pc_up}")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/deform-c.pc.in ${PROJECT_BINARY_DIR}/deform-c.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/deform-c.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)

set(DEFORM_HAVE_IMPORT_COMPONENT 0)
if(TARGET deform_import)
  set(DEFORM_HAVE_IMPORT_COMPONENT 1)
  install(TARGETS deform_import EXPORT libdeformImportTargets ${deform_install_args})
  install(TARGETS deform_import_worker RUNTIME DESTINATION ${CMAKE_INSTALL_LIBEXECDIR})
  install(EXPORT libdeformImportTargets NAMESPACE deform:: DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/libdeform/include/deform/import DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/deform)
endif()
set(DEFORM_HAVE_SIMPLIFY_COMPONENT 0)
if(TARGET deform_simplify)
  set(DEFORM_HAVE_SIMPLIFY_COMPONENT 1)
  install(TARGETS deform_simplify EXPORT libdeformSimplifyTargets ${deform_install_args})
  install(EXPORT libdeformSimplifyTargets NAMESPACE deform:: DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/libdeform/include/deform/simplify
          DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/deform)
endif()
set(DEFORM_HAVE_GPU_COMPONENT 0)
set(DEFORM_GPU_LINKS_EPOXY 0)
if(TARGET deform_gpu)
  set(DEFORM_HAVE_GPU_COMPONENT 1)
  if(NOT BUILD_SHARED_LIBS)
    set(DEFORM_GPU_LINKS_EPOXY 1)  # a static deform_gpu leaves libepoxy to the consumer's link
  endif()
  install(TARGETS deform_gpu EXPORT libdeformGpuTargets ${deform_install_args})
  install(EXPORT libdeformGpuTargets NAMESPACE deform:: DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/libdeform/include/deform/gpu DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/deform)
endif()
if(TARGET deform_cli)
  install(TARGETS deform_cli RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
endif()

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/libdeformConfig.cmake.in
  ${PROJECT_BINARY_DIR}/libdeformConfig.cmake INSTALL_DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/libdeformConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/libdeformConfig.cmake ${PROJECT_BINARY_DIR}/libdeformConfigVersion.cmake
  DESTINATION ${DEFORM_INSTALL_CMAKEDIR})
