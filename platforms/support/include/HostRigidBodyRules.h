#ifndef MRATTLE_HOST_RIGID_BODY_RULES_H_
#define MRATTLE_HOST_RIGID_BODY_RULES_H_

#include "BodyShapes.h"
#include "FiniteValues.h"
#include "ThermalVelocities.h"
#include <iosfwd>
#include <string>

namespace MRattlePlugin {

/*
 * The old names of the host-side rules, which the device code (platforms/common) still
 * calls while it is being rewritten; new code includes FiniteValues.h, BodyShapes.h and
 * ThermalVelocities.h. Remove this header once platforms/common uses those.
 */
namespace HostRigidBodyRules {

inline void requireFinite(const std::vector<OpenMM::Vec3>& values, const std::string& what) {
    FiniteValues::require(values, what);
}
inline std::vector<RigidBodyMath::Shape> classifyShapes(const RigidBodyTopology& topology,
                                                        const std::vector<OpenMM::Vec3>& positions) {
    return BodyShapes::classify(topology, positions);
}
inline int bodyDegreesOfFreedom(const std::vector<RigidBodyMath::Shape>& shapes) {
    return BodyShapes::degreesOfFreedom(shapes);
}
inline std::vector<OpenMM::Vec3> maxwellBoltzmannVelocities(const std::vector<double>& inverseMasses,
                                                            double temperature, int randomSeed) {
    return ThermalVelocities::maxwellBoltzmann(inverseMasses, temperature, randomSeed);
}
inline void scaleToTemperature(const RigidBodyTopology& topology, const std::vector<double>& inverseMasses,
                               int degreesOfFreedom, double temperature, std::vector<OpenMM::Vec3>& velocities) {
    ThermalVelocities::scaleToTemperature(topology, inverseMasses, degreesOfFreedom, temperature, velocities);
}

/**
 * The device kernel's own length prefix of its (empty) state. The checkpoint header
 * (RigidBodyCheckpointHeader) frames every kernel's state already; the Reference kernel
 * writes its state unframed. Kept, with this layout, so that the device's checkpoints
 * read and write as before until platforms/common writes its state unframed too.
 */
void writeKernelState(std::ostream& stream, const std::string& state);
std::string readKernelState(std::istream& stream);

} // namespace HostRigidBodyRules
} // namespace MRattlePlugin

#endif
