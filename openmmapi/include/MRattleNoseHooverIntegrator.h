#ifndef MRATTLE_NOSE_HOOVER_INTEGRATOR_H_
#define MRATTLE_NOSE_HOOVER_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * Constant-temperature dynamics for rigid bodies with a Nose-Hoover chain: velocity Verlet
 * with M-RATTLE (MRattleIntegrator's step) between two half steps of a chain of thermostats
 * coupled to the kinetic energy of all the System's degrees of freedom (bodies and free
 * particles, counted as getNumDegreesOfFreedom() counts them). The chain is propagated with
 * the Trotter factorisation of Martyna, Tuckerman, Tobias and Klein (1996): numMTS sub-steps,
 * each a Yoshida-Suzuki composition. The chain scales every velocity by one factor, which
 * keeps the bodies' velocities rigid, so one thermostat acts on translation and rotation
 * together (docs/ALGORITHM.md).
 *
 * The dynamics is deterministic; kinetic + potential + computeHeatBathEnergy() is conserved
 * up to the step's error. Velocities are on-step, as for MRattleIntegrator. Checkpoints hold
 * the chain's positions and velocities and restart bit for bit. Bodies, degrees of freedom
 * and errors behave as for every RigidBodyIntegrator.
 */
class OPENMM_EXPORT_MRATTLE MRattleNoseHooverIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param temperature         the temperature of the heat bath, in Kelvin (finite and > 0)
     * @param collisionFrequency  the frequency of the chain's coupling, in inverse picoseconds
     *                            (finite and >= 0; 0 leaves the dynamics MRattleIntegrator's)
     * @param stepSize            the step size, in picoseconds
     * @param chainLength         the number of thermostats in the chain (1 or more)
     * @param numMTS              the number of sub-steps of each half step of the chain (1 or more)
     * @param numYoshidaSuzuki    the order of the Yoshida-Suzuki composition of a sub-step: 1, 3, 5 or 7
     */
    MRattleNoseHooverIntegrator(double temperature, double collisionFrequency, double stepSize, int chainLength = 3,
                                int numMTS = 3, int numYoshidaSuzuki = 7);
    /** The temperature of the heat bath, in Kelvin. */
    double getTemperature() const {
        return temperature;
    }
    /** Set the temperature of the heat bath, in Kelvin (finite and > 0: the chain's masses are proportional to it). */
    void setTemperature(double temperature);
    /** The collision frequency, in inverse picoseconds. */
    double getCollisionFrequency() const {
        return collisionFrequency;
    }
    /**
     * Set the collision frequency w, in inverse picoseconds (finite and >= 0): the chain's
     * masses are Q_1 = N k_B T / w^2 and Q_j = k_B T / w^2 for N degrees of freedom.
     */
    void setCollisionFrequency(double frequency);
    /** The number of thermostats in the chain (fixed at construction). */
    int getChainLength() const {
        return chainLength;
    }
    /** The number of sub-steps of each half step of the chain (fixed at construction). */
    int getNumMultiTimeSteps() const {
        return numMTS;
    }
    /** The order of the Yoshida-Suzuki composition: 1, 3, 5 or 7 (fixed at construction). */
    int getNumYoshidaSuzukiTimeSteps() const {
        return numYoshidaSuzuki;
    }
    /**
     * The energy of the heat bath, in kJ/mol: sum_j Q_j v_j^2 / 2 + N k_B T x_1 +
     * k_B T sum_{j>1} x_j over the chain's velocities v_j and positions x_j, with this
     * integrator's temperature and frequency. Kinetic + potential + this is the conserved
     * quantity. Throws unless bound to a Context.
     */
    double computeHeatBathEnergy();

private:
    double temperature, collisionFrequency;
    int chainLength, numMTS, numYoshidaSuzuki;
};

} // namespace MRattlePlugin

#endif
