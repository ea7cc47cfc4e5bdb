# `cmake --install BUILD [--prefix DIR]`: the libraries, their headers, the reliefsim program
# and a CMake package, so that a user's project (examples/sampling-artifact) writes
#   find_package(reliefsim CONFIG REQUIRED)
#   target_link_libraries(my_test PRIVATE reliefsim::frame)
# Targets keep the names of the project's aliases: reliefsim::core, texture, maps, kernels,
# render, raster, metrics, frame (the scene, Render(), TracePixel, outputs: what a user's
# tests call). The GL runner (glref) is not installed: it is the twin's test harness.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(rs_installed_libs rs_options rs_core rs_texture rs_maps rs_kernels rs_render rs_raster
    rs_metrics rs_frame)
foreach(lib ${rs_installed_libs})
  string(REGEX REPLACE "^rs_" "" rs_export_name ${lib})
  set_target_properties(${lib} PROPERTIES EXPORT_NAME ${rs_export_name})
endforeach()
install(TARGETS ${rs_installed_libs} EXPORT reliefsimTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(TARGETS reliefsim RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
# Headers keep their project paths ("render/frame.h") under include/reliefsim.
install(DIRECTORY core texture maps kernels render raster metrics
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/reliefsim
        FILES_MATCHING PATTERN "*.h")
install(EXPORT reliefsimTargets NAMESPACE reliefsim::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/reliefsim)
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/reliefsimConfig.cmake.in
                              ${PROJECT_BINARY_DIR}/reliefsimConfig.cmake
                              INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/reliefsim)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/reliefsimConfigVersion.cmake
                                 VERSION 0.1.0 COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/reliefsimConfig.cmake
              ${PROJECT_BINARY_DIR}/reliefsimConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/reliefsim)
