# Bullet as one imported target, Bullet::Bullet, in the precision TORSION_BULLET_PRECISION names.
#
# Debian's libbullet-dev ships Bullet twice: pkg-config `bullet` (btScalar = float, the variant
# most game engines link) and `bullet-float64` (btScalar = double, libraries suffixed -float64,
# flags carrying -DBT_USE_DOUBLE_PRECISION). Debian's BulletConfig.cmake has relative include
# paths and defines no targets, so we go through pkg-config. The precision define must reach every
# translation unit that includes a Bullet header: btScalar's size changes with it, and a mismatch
# is an ODR violation that crashes at run time. The target forwards it as a usage requirement.
#
# Torsion's FEM is double (Eigen) either way; only the Bullet seam converts
# (torsion/bt_conversions.h). This file is installed with the package: TorsionConfig.cmake
# sets TORSION_BULLET_PRECISION to the precision the package was built for before including it,
# so consumers get exactly the target the build used.
#
# Sets TORSION_BULLET_PKG_MODULE, TORSION_BULLET_SCALAR_BYTES and TORSION_BULLET_NAME_SUFFIX
# ("" for double, "-float" for float: installed file names, so both can share one prefix).

if(NOT TORSION_BULLET_PRECISION STREQUAL "double" AND NOT TORSION_BULLET_PRECISION STREQUAL "float")
  message(FATAL_ERROR
    "TORSION_BULLET_PRECISION is '${TORSION_BULLET_PRECISION}', but Torsion knows only 'double' "
    "(Bullet with BT_USE_DOUBLE_PRECISION, pkg-config bullet-float64) and 'float' (pkg-config "
    "bullet). Configure again with -DTORSION_BULLET_PRECISION=double or =float.")
endif()

if(TORSION_BULLET_PRECISION STREQUAL "double")
  set(TORSION_BULLET_PKG_MODULE bullet-float64)
  set(TORSION_BULLET_SCALAR_BYTES 8)
  set(TORSION_BULLET_NAME_SUFFIX "")
else()
  set(TORSION_BULLET_PKG_MODULE bullet)
  set(TORSION_BULLET_SCALAR_BYTES 4)
  set(TORSION_BULLET_NAME_SUFFIX "-float")
endif()

if(TARGET Bullet::Bullet)
  # Made earlier by this file (another Torsion in the same project): it must be the same Bullet.
  # A Bullet::Bullet of the project's own is trusted as is.
  get_target_property(_torsion_existing_precision Bullet::Bullet INTERFACE_TORSION_BULLET_PRECISION)
  if(_torsion_existing_precision AND
     NOT _torsion_existing_precision STREQUAL TORSION_BULLET_PRECISION)
    message(FATAL_ERROR
      "Bullet::Bullet already exists for ${_torsion_existing_precision}-precision Bullet, and "
      "this Torsion needs ${TORSION_BULLET_PRECISION}: one program cannot link both (btScalar "
      "would have two sizes). Use Torsion built for ${_torsion_existing_precision} Bullet.")
  endif()
  unset(_torsion_existing_precision)
else()
  find_package(PkgConfig QUIET)
  if(PkgConfig_FOUND)
    pkg_check_modules(TORSION_BULLET QUIET IMPORTED_TARGET ${TORSION_BULLET_PKG_MODULE})
  endif()
  if(NOT TORSION_BULLET_FOUND)
    message(FATAL_ERROR
      "Torsion is configured for ${TORSION_BULLET_PRECISION}-precision Bullet, which it finds "
      "through pkg-config module '${TORSION_BULLET_PKG_MODULE}', and pkg-config could not find "
      "it. On Debian install both with `apt-get install pkg-config libbullet-dev` (libbullet-dev "
      "ships bullet.pc and bullet-float64.pc); elsewhere point PKG_CONFIG_PATH at the directory "
      "of a Bullet build's ${TORSION_BULLET_PKG_MODULE}.pc.")
  endif()
  add_library(Bullet::Bullet INTERFACE IMPORTED)
  target_link_libraries(Bullet::Bullet INTERFACE PkgConfig::TORSION_BULLET)
  set_target_properties(Bullet::Bullet PROPERTIES
                        INTERFACE_TORSION_BULLET_PRECISION ${TORSION_BULLET_PRECISION})
  if(TORSION_BULLET_PRECISION STREQUAL "double")
    # pkg-config reports the define as a raw flag; restate it as a definition so it is visible to
    # tools that read compile definitions (and survives de-duplication of options).
    target_compile_definitions(Bullet::Bullet INTERFACE BT_USE_DOUBLE_PRECISION)
  endif()
endif()
