// Velocity projection: the rigid-body motion nearest to a body's velocities, one body or four at a time.
#include "mrattle/RigidBodyMath.h"
#include "mrattle/Coordinates.h"
#include "RigidBodyMathDetail.h"
#include "TorqueCondition.h"
#include <algorithm>
#include <cmath>
#include <limits>

using Eigen::Matrix3d;
using Eigen::Vector3d;

namespace MRattlePlugin {
namespace RigidBodyMath {

namespace {

/** The rigid-body motion nearest (mass-weighted) to a body's velocities: centre, V and w. */
struct RigidMotion {
    Vector3d center, velocity, omega;
};

/**
 * The sums of the nearest rigid motion: centre and centre velocity; for a general body J
 * (six entries) and L about the centre, whose I^-1 L is left to the caller; for a linear
 * body the angular velocity itself.
 */
struct MotionSums {
    RigidMotion motion;
    double j[6], L[3];
};

template <class Velocity>
void rigidMotionSums(const BodyView& body, const double* positions, Velocity velocity, MotionSums& sums) {
    // One pass, about the body's first atom (not the origin, so the sums lose no digits to
    // a body far from it): M c' = sum m a, p = sum m v, S = sum m a a^T, l = sum m a x v with
    // a = x - x_first; then J = S - M c' c'^T and L = l - c' x p about the centre.
    const double* origin = positions + 3 * body.atoms[0];
    const double o0 = origin[0], o1 = origin[1], o2 = origin[2];
    double ma0 = 0, ma1 = 0, ma2 = 0, p0 = 0, p1 = 0, p2 = 0, l0 = 0, l1 = 0, l2 = 0;
    double s00 = 0, s01 = 0, s02 = 0, s11 = 0, s12 = 0, s22 = 0;
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double m = body.masses[atom];
        const double* x = positions + 3 * atom;
        const Vector3d v = velocity(atom);
        const double a0 = x[0] - o0, a1 = x[1] - o1, a2 = x[2] - o2;
        const double b0 = m * a0, b1 = m * a1, b2 = m * a2;
        ma0 += b0; ma1 += b1; ma2 += b2;
        p0 += m * v[0]; p1 += m * v[1]; p2 += m * v[2];
        s00 += b0 * a0; s01 += b0 * a1; s02 += b0 * a2;
        s11 += b1 * a1; s12 += b1 * a2; s22 += b2 * a2;
        l0 += b1 * v[2] - b2 * v[1];
        l1 += b2 * v[0] - b0 * v[2];
        l2 += b0 * v[1] - b1 * v[0];
    }
    const double inverseMass = 1.0 / body.totalMass;
    const double c0 = ma0 * inverseMass, c1 = ma1 * inverseMass, c2 = ma2 * inverseMass;
    RigidMotion& motion = sums.motion;
    motion.center = Vector3d(o0 + c0, o1 + c1, o2 + c2);
    motion.velocity = Vector3d(p0 * inverseMass, p1 * inverseMass, p2 * inverseMass);
    const double j00 = s00 - ma0 * c0, j01 = s01 - ma0 * c1, j02 = s02 - ma0 * c2;
    const double j11 = s11 - ma1 * c1, j12 = s12 - ma1 * c2, j22 = s22 - ma2 * c2;
    const Vector3d L(l0 - (c1 * p2 - c2 * p1), l1 - (c2 * p0 - c0 * p2), l2 - (c0 * p1 - c1 * p0));
    if (body.linear) {
        // I = j (1 - u u^T): no spin about the axis.
        const double traceJ = j00 + j11 + j22;
        Vector3d u = linearAxis(body, positions, motion.center);
        motion.omega = isPointExtent(traceJ, body.totalMass) ? Vector3d::Zero()  // a point does not rotate
                                                             : Vector3d((L - L.dot(u) * u) / traceJ);
        return;
    }
    sums.j[0] = j00; sums.j[1] = j01; sums.j[2] = j02; sums.j[3] = j11; sums.j[4] = j12; sums.j[5] = j22;
    sums.L[0] = L[0]; sums.L[1] = L[1]; sums.L[2] = L[2];
}

template <class Velocity>
RigidMotion nearestRigidMotionWith(const BodyView& body, const double* positions, Velocity velocity) {
    MotionSums sums;
    rigidMotionSums(body, positions, velocity, sums);
    if (!body.linear)
        TorqueCondition::solveInertia(sums.j, sums.L, sums.motion.omega.data());
    return sums.motion;
}

RigidMotion nearestRigidMotion(const BodyView& body, const double* positions, const double* velocities) {
    return nearestRigidMotionWith(body, positions, [&](int atom) -> Vector3d { return point(velocities, atom); });
}

/** Replace the body's atom velocities by the rigid motion's. */
void setRigidVelocities(const BodyView& body, const RigidMotion& motion, const double* positions, double* velocities) {
    const double c0 = motion.center[0], c1 = motion.center[1], c2 = motion.center[2];
    const double u0 = motion.velocity[0], u1 = motion.velocity[1], u2 = motion.velocity[2];
    const double w0 = motion.omega[0], w1 = motion.omega[1], w2 = motion.omega[2];
    for (int k = 0; k < body.numAtoms; k++) {
        const int atom = body.atoms[k];
        const double* x = positions + 3 * atom;
        double* v = velocities + 3 * atom;
        const double a0 = x[0] - c0, a1 = x[1] - c1, a2 = x[2] - c2;
        v[0] = u0 + (w1 * a2 - w2 * a1);
        v[1] = u1 + (w2 * a0 - w0 * a2);
        v[2] = u2 + (w0 * a1 - w1 * a0);
    }
}

} // namespace

void projectBodyVelocities(const BodyView& body, const double* positions, double* velocities) {
    setRigidVelocities(body, nearestRigidMotion(body, positions, velocities), positions, velocities);
}

void kickAndProjectBodyVelocities(const BodyView& body, const Kick& kick, const double* positions, double* velocities) {
    const RigidMotion motion = nearestRigidMotionWith(body, positions, KickedVelocity(kick, velocities));
    setRigidVelocities(body, motion, positions, velocities);
}

void kickAndProjectBodiesVelocities(const BodyView* bodies, int count, const Kick& kick, const double* positions,
                                    double* velocities) {
    const KickedVelocity velocity(kick, velocities);
    MotionSums sums[4];
    double j[24], L[12], omega[12];
    for (int first = 0; first < count; first += 4) {
        const int n = std::min(4, count - first);
        int general[4], numGeneral = 0;
        for (int i = 0; i < n; i++) {
            rigidMotionSums(bodies[first + i], positions, velocity, sums[i]);
            if (!bodies[first + i].linear) {
                std::copy(sums[i].j, sums[i].j + 6, j + 6 * numGeneral);
                std::copy(sums[i].L, sums[i].L + 3, L + 3 * numGeneral);
                general[numGeneral++] = i;
            }
        }
        TorqueCondition::solveInertiaUpToFour(j, L, omega, numGeneral);
        for (int g = 0; g < numGeneral; g++)
            sums[general[g]].motion.omega = Vector3d(omega[3 * g], omega[3 * g + 1], omega[3 * g + 2]);
        for (int i = 0; i < n; i++)
            setRigidVelocities(bodies[first + i], sums[i].motion, positions, velocities);
    }
}

double nonRigidVelocityFraction(const BodyView& body, const double* positions, const double* velocities) {
    const RigidMotion motion = nearestRigidMotion(body, positions, velocities);
    double scale = 0, residual = 0;
    for (int k = 0; k < body.numAtoms; k++) {
        int atom = body.atoms[k];
        Vector3d rigid = motion.velocity + motion.omega.cross(point(positions, atom) - motion.center);
        scale = std::max(scale, rigid.norm());
        residual = std::max(residual, (point(velocities, atom) - rigid).norm());
    }
    if (residual == 0)
        return 0;
    return scale > 0 ? residual / scale : std::numeric_limits<double>::infinity();
}

bool projectNonRigidBodyVelocities(const BodyView& body, const double* positions, double* velocities,
                                   double relativeTolerance) {
    if (!(nonRigidVelocityFraction(body, positions, velocities) > relativeTolerance))
        return false;
    projectBodyVelocities(body, positions, velocities);
    return true;
}

} // namespace RigidBodyMath
} // namespace MRattlePlugin
