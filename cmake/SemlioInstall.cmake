# install() + exported target + package config with a version file, so that a
# separate project can find_package(semlio) and link semlio::semlio.
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS semlio EXPORT semlioTargets)
if(SEMLIO_HAVE_BAGS)
  install(TARGETS semlio_io_bags EXPORT semlioTargets)
endif()
if(SEMLIO_HAVE_ONNX)
  install(TARGETS semlio_segment_onnx EXPORT semlioTargets)
endif()
install(DIRECTORY "${PROJECT_SOURCE_DIR}/include/semlio"
        DESTINATION "${CMAKE_INSTALL_INCLUDEDIR}")
set(SEMLIO_CMAKE_DIR "${CMAKE_INSTALL_DATADIR}/semlio/cmake")
install(EXPORT semlioTargets NAMESPACE semlio:: DESTINATION "${SEMLIO_CMAKE_DIR}")

configure_package_config_file(
  "${PROJECT_SOURCE_DIR}/cmake/semlioConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/semlioConfig.cmake"
  INSTALL_DESTINATION "${SEMLIO_CMAKE_DIR}")
# Header-only: the package is architecture-independent.
write_basic_package_version_file(
  "${PROJECT_BINARY_DIR}/semlioConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion ARCH_INDEPENDENT)
install(FILES "${PROJECT_BINARY_DIR}/semlioConfig.cmake"
              "${PROJECT_BINARY_DIR}/semlioConfigVersion.cmake"
              "${PROJECT_SOURCE_DIR}/cmake/SemlioOnnx.cmake"  # its OpenCV search, for the config
        DESTINATION "${SEMLIO_CMAKE_DIR}")
