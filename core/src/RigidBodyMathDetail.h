#ifndef MRATTLE_RIGID_BODY_MATH_DETAIL_H_
#define MRATTLE_RIGID_BODY_MATH_DETAIL_H_

// What the parts of RigidBodyMath (RigidBodyShape.cpp, RigidBodyReset.cpp,
// RigidBodyProjection.cpp) share and do not export.

#include "mrattle/RigidBodyMath.h"

namespace MRattlePlugin {
namespace RigidBodyMath {

/** Unit vector along a linear body: the direction of its atom farthest from the centre. */
Eigen::Vector3d linearAxis(const BodyView& body, const double* positions, const Eigen::Vector3d& center);

/**
 * An atom's velocity with a kick applied, as a separate pass would have stored it
 * (v + f * (time / m)); velocities as they are if there are no forces.
 */
class KickedVelocity {
public:
    KickedVelocity(const Kick& kick, const double* velocities) : kick(kick), velocities(velocities) {
    }
    Eigen::Vector3d operator()(int atom) const {
        const double* v = velocities + 3 * atom;
        if (kick.forces == nullptr)
            return Eigen::Vector3d(v[0], v[1], v[2]);
        const double* f = kick.forces + 3 * atom;
        const double scale = kick.time * kick.inverseMasses[atom];
        return Eigen::Vector3d(v[0] + f[0] * scale, v[1] + f[1] * scale, v[2] + f[2] * scale);
    }

private:
    const Kick& kick;
    const double* velocities;
};

} // namespace RigidBodyMath
} // namespace MRattlePlugin

#endif
