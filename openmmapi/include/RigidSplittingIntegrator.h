#ifndef MRATTLE_RIGID_SPLITTING_INTEGRATOR_H_
#define MRATTLE_RIGID_SPLITTING_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * The baseline M-RATTLE is compared with: the symplectic splitting method for rigid
 * bodies (Dullweber, Leimkuhler and McLachlan 1997; NO_SQUISH, Miller et al. 2002).
 * Each body's centre and angular momentum get half kicks from the net force and torque,
 * the centre drifts, and the free rotor is split into exact rotations about the
 * principal axes, x(h/2) y(h/2) z(h) y(h/2) x(h/2). Particles in no body follow velocity
 * Verlet, with RATTLE for constraints among them.
 *
 * Bodies, degrees of freedom, velocity projection, temperatures and checkpoints behave
 * exactly as for MRattleIntegrator (both derive from RigidBodyIntegrator). Velocities are
 * on-step Cartesian atom velocities V + w x a_i. The body state (orientation, principal
 * frame, angular momentum) is derived from the positions and velocities at every step,
 * so a step depends on nothing else and a restart from a checkpoint is exact. For a body
 * with two equal principal moments (e.g. benzene) the principal axes in the degenerate
 * plane are whichever the eigensolver returns: still a second-order symplectic step.
 */
class OPENMM_EXPORT_MRATTLE RigidSplittingIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param stepSize  the step size in picoseconds
     */
    explicit RigidSplittingIntegrator(double stepSize);
};

} // namespace MRattlePlugin

#endif
