# Installed, relocatable package: find_package(Torsion) gives Torsion::extension and Torsion::device.
include(CMakePackageConfigHelpers)

set(TORSION_CMAKE_INSTALL_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/Torsion")

install(EXPORT TorsionTargets
        NAMESPACE Torsion::
        DESTINATION "${TORSION_CMAKE_INSTALL_DIR}")

configure_package_config_file(
  "${PROJECT_SOURCE_DIR}/cmake/TorsionConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/TorsionConfig.cmake"
  INSTALL_DESTINATION "${TORSION_CMAKE_INSTALL_DIR}")
write_basic_package_version_file(
  "${PROJECT_BINARY_DIR}/TorsionConfigVersion.cmake"
  VERSION ${PROJECT_VERSION}
  COMPATIBILITY SameMinorVersion)

install(FILES
  "${PROJECT_BINARY_DIR}/TorsionConfig.cmake"
  "${PROJECT_BINARY_DIR}/TorsionConfigVersion.cmake"
  "${PROJECT_SOURCE_DIR}/cmake/TorsionBullet.cmake"
  "${PROJECT_SOURCE_DIR}/cmake/TorsionCholmod.cmake"
  DESTINATION "${TORSION_CMAKE_INSTALL_DIR}")
