# install() and a package config, so find_package(rtcd) works for hosts.
include(CMakePackageConfigHelpers)
# Both libraries are installed, rtcd::static and rtcd::shared; rtcd::rtcd,
# what hosts link, is the one BUILD_SHARED_LIBS chose.
if(BUILD_SHARED_LIBS)
  set(RTCD_DEFAULT_LIBRARY shared)
else()
  set(RTCD_DEFAULT_LIBRARY static)
endif()
install(TARGETS rtcd_core ${RTCD_BACKEND_TARGETS} rtcd_lib rtcd_shared rtcd_cli
  EXPORT rtcdTargets
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR}
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
# The public headers only: core/internal stays in the source tree.
install(DIRECTORY core/include/ backends/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT rtcdTargets NAMESPACE rtcd:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/rtcd)
# The Bullet host, its own component.
install(TARGETS rtcd_sim EXPORT rtcdSimTargets ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
install(DIRECTORY sim/include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT rtcdSimTargets NAMESPACE rtcd:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/rtcd)
configure_package_config_file(cmake/rtcdConfig.cmake.in ${CMAKE_CURRENT_BINARY_DIR}/rtcdConfig.cmake
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/rtcd)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/rtcdConfigVersion.cmake COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/rtcdConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/rtcdConfigVersion.cmake
  DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/rtcd)
