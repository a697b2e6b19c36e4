#pragma once
// Bullet's deformable-world headers for the side-by-side benchmark runners, included with the
// warnings our -Werror build would raise on Bullet's own code silenced (they are not ours to fix).
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wold-style-cast"
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wpedantic"
#pragma GCC diagnostic ignored "-Woverloaded-virtual"
#pragma GCC diagnostic ignored "-Wdouble-promotion"
#pragma GCC diagnostic ignored "-Wcast-align"
#pragma GCC diagnostic ignored "-Wnon-virtual-dtor"
#pragma GCC diagnostic ignored "-Wunused-variable"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wreorder"
#if !defined(__clang__)  // gcc's own warning; clang has no such group
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#endif
#include "BulletSoftBody/btDeformableBodySolver.h"
#include "BulletSoftBody/btDeformableCorotatedForce.h"
#include "BulletSoftBody/btDeformableGravityForce.h"
#include "BulletSoftBody/btDeformableLinearElasticityForce.h"
#include "BulletSoftBody/btDeformableMultiBodyConstraintSolver.h"
#include "BulletSoftBody/btDeformableMultiBodyDynamicsWorld.h"
#include "BulletSoftBody/btDeformableNeoHookeanForce.h"
#include "BulletSoftBody/btSoftBodyRigidBodyCollisionConfiguration.h"
#include "LinearMath/btPolarDecomposition.h"
#include "LinearMath/btQuickprof.h"
#include "btBulletDynamicsCommon.h"
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif
