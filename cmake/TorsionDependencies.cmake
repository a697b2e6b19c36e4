# Third-party dependencies, all from Debian packages (scripts/setup.sh installs them).
# Each one is exposed as a namespaced imported target so the rest of the build never sees paths.

find_package(Eigen3 3.3 REQUIRED NO_MODULE)
include(TorsionBullet)   # Bullet::Bullet, in TORSION_BULLET_PRECISION
if(TORSION_CHOLMOD)
  include(TorsionCholmod)  # SuiteSparse::CHOLMOD
endif()
find_package(TBB REQUIRED)

find_package(CLI11 REQUIRED)  # headers only: the torsion tool and the haptic peer's options
if(TORSION_BUILD_DEMOS)
  find_package(nlohmann_json 3.10 REQUIRED)
  find_package(ZLIB)  # optional: compresses the ParaView series (demos/series/vtu_writer.h)
endif()
