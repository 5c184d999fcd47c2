#ifndef MRATTLE_RIGID_BODY_ROTOR_H_
#define MRATTLE_RIGID_BODY_ROTOR_H_

/*
 * The baseline M-RATTLE is compared with: the symplectic splitting of rigid-body motion
 * (Dullweber, Leimkuhler and McLachlan 1997; NO_SQUISH, Miller et al. 2002). The free
 * rotor is split into exact rotations about the principal axes, in the symmetric
 * sequence x(h/2) y(h/2) z(h) y(h/2) x(h/2).
 *
 * The body state (centre, orientation, body-frame sites, principal moments, angular
 * momentum) is derived afresh from the atoms' positions and rigid velocities at each
 * step, so a step depends only on the Cartesian state: restarts are exact and nothing
 * but positions and velocities needs to be stored. For equal moments the frame is taken
 * from the atoms (it turns with the body), which keeps the step time-reversible.
 */

#include "mrattle/RigidBodyMath.h"
#include <Eigen/Dense>

namespace MRattlePlugin {
namespace RigidBodyRotor {

/** The largest turn of a body in one step that the splitting integrator accepts: a quarter turn. */
constexpr double MaxRotationPerStep = 1.5707963267948966;

/** Principal axes (columns, a proper rotation: body frame -> space frame) and moments, ascending. */
struct PrincipalFrame {
    Eigen::Matrix3d axes;
    Eigen::Vector3d moments;
};

/**
 * Principal frame of a body with second moment J = sum m_i a_i a_i^T (inertia tr(J) 1 - J).
 * The moments are in ascending order, so a linear body's zero moment (its axis) is first.
 */
PrincipalFrame principalFrame(const Eigen::Matrix3d& secondMoment);

/**
 * The principal frame of a body, with the basis of a degenerate plane (equal moments: a
 * symmetric or spherical top, such as benzene) taken from the body's own atoms, so that it
 * turns with the body and the splitting step is exactly time-reversible. Linear bodies
 * keep principalFrame(J)'s basis.
 */
PrincipalFrame principalFrame(const Eigen::Matrix3d& secondMoment, const RigidBodyMath::BodyView& body,
                              const double* positions, const Eigen::Vector3d& center);

/** Rotation by angle about body axis 0, 1 or 2 (right-handed). */
Eigen::Matrix3d axisRotation(int axis, double angle);

/**
 * Free rotor over time h by the sequence x(h/2) y(h/2) z(h) y(h/2) x(h/2) of exact
 * rotations about the principal axes: for axis k over time t, theta = t Pi_k / I_k,
 * R <- R R_k(theta), Pi <- R_k(theta)^T Pi. With linear set, axis 0 (zero moment) is
 * skipped and Pi_0 is taken as zero.
 *
 * @param moments          principal moments I_0 <= I_1 <= I_2
 * @param bodyMomentum     body-frame angular momentum Pi; advanced in place
 * @return the body-frame rotation R accumulated over the step (orientation Q -> Q R)
 */
Eigen::Matrix3d freeRotorStep(const Eigen::Vector3d& moments, Eigen::Vector3d& bodyMomentum, double h, bool linear);

/**
 * Position half of one splitting step for one body. From positions x, rigid velocities
 * v and forces f at the start of the step: half kick of momentum and angular momentum,
 * drift of the centre, free rotor. Writes, for the body's atoms only, the new positions
 * x_i = R + Q d_i and half-step rigid velocities V + w x a_i (a_i about the new centre)
 * whose momentum and angular momentum are the half-kicked ones; a Cartesian half kick
 * followed by RigidBodyMath::projectBodyVelocities then completes the step exactly.
 * All arrays are 3N doubles indexed by global atom.
 *
 * @return false, with nothing written, if the result is not finite or the body would turn
 *         by more than MaxRotationPerStep radians in the step (the step is too large)
 */
bool positionStep(const RigidBodyMath::BodyView& body, const double* positions, const double* velocities,
                  const double* forces, double h, double* newPositions, double* newVelocities);

} // namespace RigidBodyRotor
} // namespace MRattlePlugin

#endif
