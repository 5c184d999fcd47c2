#ifndef MRATTLE_LANGEVIN_INTEGRATOR_H_
#define MRATTLE_LANGEVIN_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * Langevin dynamics (constant temperature) for rigid bodies: OpenMM's
 * LangevinMiddleIntegrator splitting with M-RATTLE. One step is a kick with the forces at
 * the current positions followed by the rigid-body velocity projection, a half drift with
 * the M-RATTLE reset of each body, the Ornstein-Uhlenbeck update of the velocities
 * (friction and Gaussian noise) followed by the projection, and a second half drift with
 * reset (docs/ALGORITHM.md derives it). Free particles follow LangevinMiddle with RATTLE
 * for their constraints.
 *
 * As with LangevinMiddleIntegrator, the velocities kept (and reported) are those of the
 * middle of the last step, after the noise: the ones whose kinetic temperature is
 * accurate. At zero friction the noise step is the identity, the two half drifts are
 * taken as one, and the positions are MRattleIntegrator's.
 *
 * Bodies, degrees of freedom, checkpoints (which hold the random stream) and errors behave
 * as for every RigidBodyIntegrator.
 */
class OPENMM_EXPORT_MRATTLE MRattleLangevinIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param temperature    the temperature of the heat bath, in Kelvin
     * @param frictionCoeff  the friction coefficient which couples the system to the heat bath, in inverse picoseconds
     * @param stepSize       the step size with which to integrate the system, in picoseconds
     */
    MRattleLangevinIntegrator(double temperature, double frictionCoeff, double stepSize);
    /** The temperature of the heat bath, in Kelvin. */
    double getTemperature() const {
        return temperature;
    }
    /** Set the temperature of the heat bath, in Kelvin (finite and >= 0). */
    void setTemperature(double temperature);
    /** The friction coefficient, in inverse picoseconds. */
    double getFriction() const {
        return friction;
    }
    /** Set the friction coefficient, in inverse picoseconds (finite and >= 0). */
    void setFriction(double coeff);
    /** The seed of the random stream (0: a new one each time a Context is created). */
    int getRandomNumberSeed() const {
        return randomNumberSeed;
    }
    /**
     * Set the seed of the random stream. Two Contexts with the same seed draw the same noise;
     * 0 (the default) picks a new seed each time a Context is created. A checkpoint restores
     * the stream as it was, whatever the seed. On a device platform (OpenCL, CUDA) OpenMM has
     * one random generator per Context: a System that also has an AndersenThermostat draws
     * from the generator seeded with the thermostat's seed.
     */
    void setRandomNumberSeed(int seed) {
        randomNumberSeed = seed;
    }

    /**
     * The velocities are those of the middle of the step: half a step behind the positions,
     * as for LangevinMiddleIntegrator (Context::setVelocitiesToTemperature uses this).
     */
    double getVelocityTimeOffset() const override {
        return getStepSize() / 2;
    }

private:
    double temperature, friction;
    int randomNumberSeed = 0;
};

} // namespace MRattlePlugin

#endif
