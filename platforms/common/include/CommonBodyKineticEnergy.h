#ifndef MRATTLE_COMMON_BODY_KINETIC_ENERGY_H_
#define MRATTLE_COMMON_BODY_KINETIC_ENERGY_H_

#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeKernel.h"

namespace MRattlePlugin {

/**
 * The kinetic energy of the Context's velocities split into the rigid bodies' translation,
 * their rotation and the free particles, on OpenMM's common compute platforms
 * (RigidBodyState::computeKineticEnergies()). The bodies' parts come from the device
 * (kernels/bodyKineticEnergy.cc, one work item per body); the free part is OpenMM's kinetic
 * energy of all particles minus the bodies' atoms', so the three add up to it. The program is
 * compiled at the first call: Contexts that never ask pay nothing.
 */
class CommonBodyKineticEnergy {
public:
    /**
     * @param bodyStart  numBodies + 1 offsets into bodyAtoms
     * @param bodyAtoms  the bodies' atoms, device atom indices (the owner keeps them current
     *                   when atoms are reordered); both arrays must outlive this object
     */
    CommonBodyKineticEnergy(OpenMM::ComputeContext& cc, int numBodies, OpenMM::ComputeArray& bodyStart,
                            OpenMM::ComputeArray& bodyAtoms);
    /** The three sums, in kJ/mol. */
    void compute(double& translational, double& rotational, double& free);

private:
    OpenMM::ComputeContext& cc;
    const int numBodies;
    OpenMM::ComputeArray &bodyStart, &bodyAtoms;
    OpenMM::ComputeArray energies;  // 3 per body, 'mixed' precision
    OpenMM::ComputeKernel kernel;
};

} // namespace MRattlePlugin

#endif
