#ifndef MRATTLE_INTEGRATOR_H_
#define MRATTLE_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * Velocity Verlet in Cartesian coordinates that keeps molecules rigid with M-RATTLE:
 * per body, 3 translational and 3 rotational conditions reset the coordinates after each
 * drift and the velocities after each kick, whatever the number of constraints. It is
 * algebraically equivalent to RATTLE with a complete set of distance constraints, needs
 * no constraint expressions (planar molecules such as benzene work), and forces between
 * atoms of one body never affect the motion.
 *
 * It is a drop-in replacement for VerletIntegrator: velocities are on-step (like
 * OpenMM's velocity-Verlet integrators), and every step calls updateContextState() so
 * CMMotionRemover, AndersenThermostat and barostats act.
 */
class OPENMM_EXPORT_MRATTLE MRattleIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param stepSize  the step size in picoseconds
     */
    explicit MRattleIntegrator(double stepSize);
};

} // namespace MRattlePlugin

#endif
