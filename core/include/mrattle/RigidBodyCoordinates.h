#ifndef MRATTLE_RIGID_BODY_COORDINATES_H_
#define MRATTLE_RIGID_BODY_COORDINATES_H_

/*
 * A body's rigid-body coordinates, as the rigid minimizer searches over them: a translation
 * of its centroid and a rotation vector applied to its shape. Positions, forces and masses
 * are 3N-double arrays and particle-indexed arrays (no OpenMM types), as elsewhere in the core.
 */
#include <Eigen/Dense>
#include <vector>

namespace MRattlePlugin {
namespace RigidBodyMath {

/** [w]x, the matrix of w x (cross product). */
inline Eigen::Matrix3d crossMatrix(const Eigen::Vector3d& w) {
    Eigen::Matrix3d m;
    m << 0, -w.z(), w.y(),
         w.z(), 0, -w.x(),
         -w.y(), w.x(), 0;
    return m;
}

/** d/dt exp([theta + t d]x) = [J(theta) d]x exp([theta]x): the left Jacobian J of SO(3). */
Eigen::Matrix3d leftJacobian(const Eigen::Vector3d& theta);

/** The centroid (unweighted mean) of the listed atoms of a 3N-double position array. */
Eigen::Vector3d centroid(const double* positions, const std::vector<int>& atoms);

/**
 * One body: atom k sits at center + scale u / sqrt(n) + R(theta) base shape_k, with shape_k
 * its offset from the centroid when the coordinates were made (never changed), base the
 * rotation folded in so far and theta = axes (scale v) a rotation vector. The variables u (3)
 * and v (one per rotation) make the metric of the atoms' displacements the identity at
 * u = v = 0 (|dx|^2 = scale^2 (|du|^2 + |dv|^2), unit masses), so the gradient in them is
 * the force projected on rigid motion. The centroid makes translation and rotation
 * orthogonal in that metric. `variables` below is the body's own block of numVariables().
 */
class RigidBodyCoordinates {
public:
    /** The body of these atoms, its shape taken from `positions`; u = v = 0 there (after restartAt). */
    RigidBodyCoordinates(const std::vector<int>& atoms, const double* positions);
    /**
     * Restart the variables about a new placement of the body: the centroid of `positions`,
     * the rotations about the principal axes of the unit-mass inertia at orientation base
     * (the identity if resetOrientation). A linear body gets two rotations, a point none, by
     * the kernels' rule (classifyShape() of the mass-weighted second moment).
     */
    void restartAt(const double* positions, const double* masses, bool resetOrientation);
    /** Fold the rotation of `variables` into base (then restartAt(..., false) about the new positions). */
    void foldRotation(const double* variables, double scale);
    int numVariables() const { return 3 + (int) axes.cols(); }
    const std::vector<int>& getAtoms() const { return atoms; }
    /** Its centroid and rotation vector at `variables` (scale: length per unit of the variables). */
    Eigen::Vector3d centroidAt(const double* variables, double scale) const;
    Eigen::Vector3d rotationVector(const double* variables, double scale) const;
    /** Write its atoms' positions at `variables` into the 3N array `positions`. */
    void place(const double* variables, double scale, double* positions) const;
    /**
     * The gradient of the energy in its variables (into `gradient`, scaled by `scale`) from
     * the forces on its atoms at `positions` (as place() wrote them): dE/du = -F/sqrt(n),
     * dE/dv = -axes^T J(theta)^T tau, with F the net force and tau the torque about the
     * centroid. Returns |F|^2/n + tau . I^-1 tau (unit masses, present orientation): the
     * squared norm of the force projected on rigid motion.
     */
    double gradient(const double* variables, double scale, const double* positions, const double* forces,
                    double* gradient) const;
    /**
     * The Cartesian force on each atom projected on the body's rigid motion (unit masses):
     * F/n + w x (x_k - centroid), with w = I^-1 tau over the rotations it has. Written into
     * the 3N array `projected`; the squared norm over its atoms is gradient()'s return value.
     */
    void projectForces(const double* variables, double scale, const double* positions, const double* forces,
                       double* projected) const;

private:
    std::vector<int> atoms;
    std::vector<Eigen::Vector3d> shape;
    Eigen::Matrix3d base = Eigen::Matrix3d::Identity();
    Eigen::Vector3d center = Eigen::Vector3d::Zero();
    Eigen::Matrix<double, 3, Eigen::Dynamic> axes;  // columns: principal axis / sqrt(moment)
    double sqrtAtoms = 1;
    /** The net force and the torque about the centroid at `variables`. */
    void forceAndTorque(const double* variables, double scale, const double* positions, const double* forces,
                        Eigen::Vector3d& force, Eigen::Vector3d& torque) const;
};

} // namespace RigidBodyMath
} // namespace MRattlePlugin

#endif
