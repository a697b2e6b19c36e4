#pragma once
// Values a scene may state but the arithmetic cannot carry: refused at load, naming the bound,
// instead of running into inf or NaN that a step would then report as converged or stable.

#include "torsion/fem/material.h"
#include "torsion/mesh/tet_mesh.h"
#include "torsion/result.h"

namespace torsion::scene {

/// |gravity| above this (m/s^2, 10^5 g) is refused.
inline constexpr double kMaxGravity = 1e6;
/// The stiffness-to-inertia ratio E dt^2 / (rho h^2) (h: the shortest edge) above this is
/// refused: the step's matrix entries and their squares in the solver's norms must stay finite.
inline constexpr double kMaxStiffnessRatio = 1e100;
/// Rigid-body lengths (sizes, margins, hull points) above this (m) are refused: Bullet forms
/// inertias ~ mass * size^2 and products of them.
inline constexpr double kMaxRigidLength = 1e6;
/// Where bodies are placed (a body's pose position, a rigid body's, the ground's height), m
/// from the origin: beyond it a unit-sized body's coordinates lose their digits (1e300 + 1 ==
/// 1e300) and the first step returns inf or NaN.
inline constexpr double kMaxPlacement = 1e6;
/// An FEM body's starting speed (m/s) and spin (rad/s) above this are refused: a step moves a
/// node by dt v, and products of such speeds with masses and lengths lose every digit of the
/// body's size (1e6 m/s covers any impact a solid survives; sound in steel is 6e3 m/s).
inline constexpr double kMaxInitialSpeed = 1e6;
inline constexpr double kMaxInitialSpin = 1e6;
/// A dynamic rigid body's mass, kg: Bullet divides by it and multiplies it by sizes squared; at
/// 1e300 or 1e-300 a contact impulse overflows in the first step.
inline constexpr double kMinRigidMass = 1e-9;
inline constexpr double kMaxRigidMass = 1e12;

/// "magnitude 1e+160 m/s^2 is above the bound 1e+06 m/s^2 ..." or Ok; the caller names where
/// the gravity came from (the scene parser: its key path).
Status checkGravity(const Eigen::Vector3d& gravity);

/// Checks E dt^2 / (rho h^2) for a body's material on its mesh.
Status checkStiffnessRatio(const Material& material, const TetMesh& mesh, double dt);

}  // namespace torsion::scene
