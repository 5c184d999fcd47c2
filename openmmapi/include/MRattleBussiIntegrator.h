#ifndef MRATTLE_BUSSI_INTEGRATOR_H_
#define MRATTLE_BUSSI_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * Constant-temperature dynamics for rigid bodies by stochastic velocity rescaling (CSVR;
 * Bussi, Donadio and Parrinello, J. Chem. Phys. 126, 014101, 2007): velocity Verlet with
 * M-RATTLE (MRattleIntegrator's step) between two half steps of the thermostat, each of
 * which draws the new kinetic energy of all the System's degrees of freedom (bodies and
 * free particles, counted as getNumDegreesOfFreedom() counts them) exactly from the
 * paper's process, the gamma-distributed sum included, and scales every velocity by one
 * factor. Scaling keeps the bodies' velocities rigid, so one thermostat acts on translation
 * and rotation together (docs/ALGORITHM.md). The dynamics between the rescalings is
 * Hamiltonian, so dynamical quantities (diffusion) are little disturbed at weak coupling.
 *
 * The energy the thermostat has taken out of the System, computeHeatBathEnergy() (minus the
 * accumulated work of the rescalings), makes kinetic + potential + it a conserved quantity
 * up to the step's error (the paper's effective energy). Velocities are on-step. The
 * random stream and the accumulated work are checkpointed and restart bit for bit. Bodies,
 * degrees of freedom and errors behave as for every RigidBodyIntegrator.
 */
class OPENMM_EXPORT_MRATTLE MRattleBussiIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param temperature         the temperature of the heat bath, in Kelvin (finite and >= 0)
     * @param collisionFrequency  the inverse of the thermostat's time constant, in inverse
     *                            picoseconds (finite and >= 0; 0 leaves the dynamics MRattleIntegrator's)
     * @param stepSize            the step size, in picoseconds
     */
    MRattleBussiIntegrator(double temperature, double collisionFrequency, double stepSize);
    /** The temperature of the heat bath, in Kelvin. */
    double getTemperature() const {
        return temperature;
    }
    /** Set the temperature of the heat bath, in Kelvin (finite and >= 0). */
    void setTemperature(double temperature);
    /** The collision frequency 1 / tau, in inverse picoseconds. */
    double getCollisionFrequency() const {
        return collisionFrequency;
    }
    /** Set the collision frequency 1 / tau, in inverse picoseconds (finite and >= 0). */
    void setCollisionFrequency(double frequency);
    /** The time constant tau = 1 / collision frequency, in picoseconds (infinite at frequency 0). */
    double getTimeConstant() const;
    /** Set the time constant tau, in picoseconds (> 0, infinity allowed: no coupling). */
    void setTimeConstant(double tau);
    /** The seed of the random stream (0: a new one each time a Context is created). */
    int getRandomNumberSeed() const {
        return randomNumberSeed;
    }
    /**
     * Set the seed of the random stream: two Contexts with the same seed draw the same
     * numbers; 0 (the default) picks a new seed each time a Context is created. A checkpoint
     * restores the stream as it was, whatever the seed.
     */
    void setRandomNumberSeed(int seed) {
        randomNumberSeed = seed;
    }
    /**
     * The energy the thermostat has taken out of the System since the Context was created
     * (or reinitialized), in kJ/mol: minus the sum of the kinetic-energy changes of every
     * rescaling. Kinetic + potential + this is conserved up to the step's error. Throws
     * unless bound to a Context.
     */
    double computeHeatBathEnergy();

private:
    double temperature, collisionFrequency;
    int randomNumberSeed = 0;
};

} // namespace MRattlePlugin

#endif
