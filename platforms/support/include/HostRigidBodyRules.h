#ifndef MRATTLE_HOST_RIGID_BODY_RULES_H_
#define MRATTLE_HOST_RIGID_BODY_RULES_H_

#include "RigidBodyTopology.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/Vec3.h"
#include <iosfwd>
#include <string>
#include <vector>

namespace MRattlePlugin {

/*
 * The host-side rules every platform's kernels apply the same way (Reference, CPU and the
 * device platforms' host code call these; none has its own copy).
 */
namespace HostRigidBodyRules {

/** Throw an OpenMMException naming the first particle whose value (`what`: "position", ...) is not finite. */
void requireFinite(const std::vector<OpenMM::Vec3>& values, const std::string& what);

/** Each body's shape (general, linear, a point) at these positions. */
std::vector<RigidBodyMath::Shape> classifyShapes(const RigidBodyTopology& topology,
                                                 const std::vector<OpenMM::Vec3>& positions);

/** The bodies' degrees of freedom for these shapes: 6 each, 5 if linear, 3 if a point. */
int bodyDegreesOfFreedom(const std::vector<RigidBodyMath::Shape>& shapes);

/**
 * Maxwell-Boltzmann velocities at this temperature for every massive particle (massless
 * ones get zero), from a generator seeded with randomSeed: what a kernel then projects
 * onto the rigid degrees of freedom.
 */
std::vector<OpenMM::Vec3> maxwellBoltzmannVelocities(const std::vector<double>& inverseMasses, double temperature,
                                                     int randomSeed);

/**
 * Finish setVelocitiesToTemperature() once the velocities are rigid: remove the centre of
 * mass motion if the System has a CMMotionRemover, then rescale to exactly this temperature
 * with the given degrees of freedom.
 */
void scaleToTemperature(const RigidBodyTopology& topology, const std::vector<double>& inverseMasses,
                        int degreesOfFreedom, double temperature, std::vector<OpenMM::Vec3>& velocities);

/** Write a kernel's own checkpoint data: its length, then the bytes. */
void writeKernelState(std::ostream& stream, const std::string& state);
/** Read what writeKernelState() wrote; throws an OpenMMException saying what is wrong if it is truncated or malformed. */
std::string readKernelState(std::istream& stream);

} // namespace HostRigidBodyRules
} // namespace MRattlePlugin

#endif
