# Installed, relocatable package: find_package(Torsion) gives Torsion::extension and Torsion::device.
#
# Both Bullet precisions can live in one prefix. Everything a precision changes has its own name:
# the targets file TorsionTargets-<precision>.cmake and the libraries and tools built on Bullet
# (suffix TORSION_BULLET_NAME_SUFFIX, "-float" for float). The remaining files (TorsionConfig,
# headers, Torsion::device, the haptic peer) do not depend on Bullet and are the same in both.
# TorsionConfig.cmake picks the targets file the consumer asks for (docs/bullet-integration.md).
include(CMakePackageConfigHelpers)

set(TORSION_CMAKE_INSTALL_DIR "${CMAKE_INSTALL_LIBDIR}/cmake/Torsion")

install(EXPORT TorsionTargets
        FILE "TorsionTargets-${TORSION_BULLET_PRECISION}.cmake"
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
  DESTINATION "${TORSION_CMAKE_INSTALL_DIR}")
# Only a build with CHOLMOD installs its finder; TorsionConfig.cmake looks for CHOLMOD when it is
# there (a prefix holding one build with and one without CHOLMOD asks for it).
if(TORSION_CHOLMOD)
  install(FILES "${PROJECT_SOURCE_DIR}/cmake/TorsionCholmod.cmake"
          DESTINATION "${TORSION_CMAKE_INSTALL_DIR}")
endif()
