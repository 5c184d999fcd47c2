#ifndef MRATTLE_THERMAL_VELOCITIES_H_
#define MRATTLE_THERMAL_VELOCITIES_H_

#include "RigidBodyTopology.h"
#include "openmm/Vec3.h"
#include "internal/windowsExportMRattle.h"
#include <vector>

namespace MRattlePlugin {

/** setVelocitiesToTemperature() on every platform: draw, (the kernel projects,) rescale. */
namespace ThermalVelocities {

/**
 * Maxwell-Boltzmann velocities at this temperature for every massive particle (massless
 * ones get zero), from a generator seeded with randomSeed: what a kernel then projects
 * onto the rigid degrees of freedom.
 */
OPENMM_EXPORT_MRATTLE std::vector<OpenMM::Vec3> maxwellBoltzmann(const std::vector<double>& inverseMasses, double temperature,
                                                                 int randomSeed);

/**
 * Finish once the velocities are rigid: remove the centre of mass motion if the System
 * has a CMMotionRemover, then rescale to exactly this temperature with the given degrees
 * of freedom.
 */
OPENMM_EXPORT_MRATTLE void scaleToTemperature(const RigidBodyTopology& topology, const std::vector<double>& inverseMasses,
                        int degreesOfFreedom, double temperature, std::vector<OpenMM::Vec3>& velocities);

} // namespace ThermalVelocities
} // namespace MRattlePlugin

#endif
