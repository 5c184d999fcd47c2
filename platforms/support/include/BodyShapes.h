#ifndef MRATTLE_BODY_SHAPES_H_
#define MRATTLE_BODY_SHAPES_H_

#include "RigidBodyTopology.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/Vec3.h"
#include <vector>

namespace MRattlePlugin {

/** Which shape each body has at given positions, and the degrees of freedom that gives: every platform's rule. */
namespace BodyShapes {

/** Each body's shape (general, linear, a point) at these positions. */
std::vector<RigidBodyMath::Shape> classify(const RigidBodyTopology& topology, const std::vector<OpenMM::Vec3>& positions);

/** The bodies' degrees of freedom for these shapes: 6 each, 5 if linear, 3 if a point. */
int degreesOfFreedom(const std::vector<RigidBodyMath::Shape>& shapes);

} // namespace BodyShapes
} // namespace MRattlePlugin

#endif
