# Bullet in double precision as one imported target, Bullet::Bullet.
#
# Debian's BulletConfig.cmake has relative include paths and defines no targets, so we go through
# pkg-config's bullet-float64 module, whose flags carry -DBT_USE_DOUBLE_PRECISION. That define must
# reach every translation unit that includes a Bullet header: btScalar's size changes with it, and
# a mismatch is an ODR violation that crashes at run time. The target forwards it as a usage
# requirement. This file is installed with the package so consumers get the same target.

if(NOT TARGET Bullet::Bullet)
  find_package(PkgConfig REQUIRED)
  pkg_check_modules(TORSION_BULLET_F64 REQUIRED IMPORTED_TARGET bullet-float64)
  add_library(Bullet::Bullet INTERFACE IMPORTED)
  target_link_libraries(Bullet::Bullet INTERFACE PkgConfig::TORSION_BULLET_F64)
  # pkg-config reports the define as a raw flag; restate it as a definition so it is visible to
  # tools that read compile definitions (and survives de-duplication of options).
  target_compile_definitions(Bullet::Bullet INTERFACE BT_USE_DOUBLE_PRECISION)
endif()
