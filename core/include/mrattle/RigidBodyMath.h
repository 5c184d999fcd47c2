#ifndef MRATTLE_RIGID_BODY_MATH_H_
#define MRATTLE_RIGID_BODY_MATH_H_

/*
 * The numerical core of M-RATTLE: the per-body position reset (a rotation solve of
 * 3 conditions) and the velocity projection onto rigid-body motion. Free of OpenMM
 * types so that it can be unit-tested and benchmarked on its own.
 *
 * Coordinates are arrays of 3N doubles (x0,y0,z0,x1,...), indexed by global atom index;
 * a body names its atoms through an index list, so the kernel never gathers or copies.
 */

#include <Eigen/Dense>

namespace MRattlePlugin {
namespace RigidBodyMath {

/** One rigid body as the core sees it: atom indices into global arrays. */
struct BodyView {
    const int* atoms;       // global indices of the body's atoms
    int numAtoms;
    const double* masses;   // per global atom index
    double totalMass;
    bool linear;            // collinear atoms: 5 degrees of freedom
};

/** Result of the rotation solve of one position reset. */
struct RotationSolve {
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    Eigen::Matrix3d rotationMinusIdentity = Eigen::Matrix3d::Zero();  // rotation - 1, without cancellation
    int iterations = 0;
    bool converged = false;
};

/** Newton iterations allowed before the solve is reported as not converged. */
constexpr int MaxRotationIterations = 50;
/**
 * The rotation solve has converged when its error estimate, step^2 / previous step, is
 * below this fraction of the rotation (double precision's round-off)...
 */
constexpr double ChordConvergence = 1e-15;
/** ...and keeps its Jacobian (chord steps) once a correction is below this fraction of the rotation. */
constexpr double ChordSwitch = 1e-3;
/**
 * Velocities of a body differing from their rigid projection by more than this fraction of
 * its largest rigid velocity have collided (an AndersenThermostat re-drew some of its atoms).
 */
constexpr double CollisionThreshold = 1e-8;

/** Mass-weighted centre of the body's atoms. */
Eigen::Vector3d centerOfMass(const BodyView& body, const double* positions);

/** J = sum m_i a_i a_i^T with a_i = x_i - center. The inertia tensor is tr(J) 1 - J. */
Eigen::Matrix3d secondMoment(const BodyView& body, const double* positions, const Eigen::Vector3d& center);

/**
 * True if the second moment J describes collinear atoms: its middle eigenvalue is below
 * 1e-12 of the largest, i.e. the atoms lie within 1e-6 of the body's length from a line.
 * Also true for a body whose atoms all coincide (no extent at all).
 */
bool isLinearShape(const Eigen::Matrix3d& secondMoment);

/** What a body's shape allows: general (6 degrees of freedom), linear (5) or a point (3). */
enum class Shape { General, Linear, Point };

/**
 * Classify a body from its second moment J and mass: a point if its atoms all lie within
 * 1e-10 nm (rms) of its centre, else linear if isLinearShape(J), else general.
 */
Shape classifyShape(const Eigen::Matrix3d& secondMoment, double totalMass);

/** Degrees of freedom of a body of that shape. */
inline int degreesOfFreedom(Shape shape) {
    return shape == Shape::General ? 6 : shape == Shape::Linear ? 5 : 3;
}

/** Rotation exp([d]x) by Rodrigues' formula (series near zero). */
Eigen::Matrix3d rotationFromVector(const Eigen::Vector3d& d);

/**
 * Solve r(P) = vex(P J - J P^T) - vex(Y - Y^T) = 0 for P in SO(3): zero torque of the
 * constraint displacement about the old positions. J: second moment at the old positions;
 * Y = sum m_i y_i a_i^T. P is the Cayley rotation of a vector w, on which the condition is
 * a quadratic solved by Newton from its linearisation (chord steps near the root); a
 * thermal step takes the linear solve and two more iterations (`iterations` counts all).
 * If it does not converge, `converged` is false and `rotation` the identity.
 * Not for linear bodies (the Jacobian is singular there; see resetBodyPositions).
 */
RotationSolve solveResetRotation(const Eigen::Matrix3d& J, const Eigen::Matrix3d& Y);

/**
 * The same solve given the torque target vex(Y - Y^T) = sum m_i a_i x y_i directly. Pass it
 * formed from displacements, sum m_i a_i x (y_i - a_i), which is equal and keeps the
 * digits of a small rotation (what resetBodyPositions does).
 */
RotationSolve solveResetRotationForTorque(const Eigen::Matrix3d& J, const Eigen::Vector3d& target);

/**
 * M-RATTLE position reset of one body. oldPositions holds x at the start of the step;
 * newPositions holds the unconstrained drift y* on entry and the reset positions
 * c_new + P (x_i - c_old) on exit (only the body's atoms are touched). If the solve does not
 * converge, nothing is written.
 */
RotationSolve resetBodyPositions(const BodyView& body, const double* oldPositions, double* newPositions);

/**
 * One body's drift and M-RATTLE position reset, from velocities: on entry velocities hold
 * the half-kicked v_i; on exit newPositions holds x_i + h V + (P - 1)(x_i - c) and
 * velocities hold V + (P - 1)(x_i - c) / h, which is (x_new - x) / h formed from
 * displacements, so neither loses digits however far the body is from the origin.
 * Only the body's atoms are touched; positions is not modified. If the solve does not
 * converge, nothing is written.
 */
RotationSolve driftAndResetBody(const BodyView& body, double stepSize, const double* positions, double* velocities,
                                double* newPositions);

/**
 * A velocity Verlet kick folded into a body's passes over its atoms: each atom's velocity is
 * read as v + f (time / m), the arithmetic of a separate kick, without a pass of its own.
 * With no forces there is no kick.
 */
struct Kick {
    const double* forces = nullptr;         // 3 per particle, like positions
    const double* inverseMasses = nullptr;  // 1 per particle
    double time = 0;
};

/**
 * The kick, then driftAndResetBody, in the same passes: velocities (not modified) hold v_i
 * before the kick; newVelocities receives what driftAndResetBody leaves in velocities.
 * Nothing is written if the solve does not converge.
 */
RotationSolve kickDriftAndResetBody(const BodyView& body, const Kick& kick, double stepSize, const double* positions,
                                    const double* velocities, double* newPositions, double* newVelocities);

/**
 * kickDriftAndResetBody for count bodies (no atom in two of them). Their rotation solves
 * are done four at a time, in the lanes of SIMD registers where the CPU has AVX2; each
 * body's result is bit for bit the one-body function's. Returns the index of the first body
 * whose reset failed (bodies before it are written, later ones may be), or count.
 */
int kickDriftAndResetBodies(const BodyView* bodies, int count, const Kick& kick, double stepSize,
                            const double* positions, const double* velocities, double* newPositions,
                            double* newVelocities);

/**
 * RATTLE's velocity step for one body: replace the body's atom velocities by their
 * mass-weighted projection onto rigid-body motion at the given positions,
 * v_i = V + w x a_i with V the centre-of-mass velocity and w = I^-1 L.
 */
void projectBodyVelocities(const BodyView& body, const double* positions, double* velocities);

/** The kick, then projectBodyVelocities, in the same passes (the kicked velocities are not stored). */
void kickAndProjectBodyVelocities(const BodyView& body, const Kick& kick, const double* positions, double* velocities);

/**
 * kickAndProjectBodyVelocities for count bodies, four at a time: their inertia solves share
 * AVX2 lanes where the CPU has them; each body's result is bit for bit the one-body function's.
 */
void kickAndProjectBodiesVelocities(const BodyView* bodies, int count, const Kick& kick, const double* positions,
                                    double* velocities);

/**
 * How far a body's velocities are from rigid-body motion: the largest distance of an atom's
 * velocity from the projection's, over the largest velocity of the projection (0 for
 * rigid motion, infinite for velocities with no rigid part at all).
 */
double nonRigidVelocityFraction(const BodyView& body, const double* positions, const double* velocities);

/**
 * Velocities that are already rigid to round-off stay bit for bit as they are (projecting
 * them again would change them at round-off, and restarts would no longer be exact);
 * others are replaced by projectBodyVelocities(). Rigid means every atom's velocity is
 * nonRigidVelocityFraction() <= relativeTolerance.
 *
 * @return true if the velocities were projected
 */
bool projectNonRigidBodyVelocities(const BodyView& body, const double* positions, double* velocities,
                                   double relativeTolerance);

/** The relative tolerance below which velocities count as rigid (round-off of a projection). */
constexpr double RigidVelocityTolerance = 1e-12;

} // namespace RigidBodyMath
} // namespace MRattlePlugin

#endif
