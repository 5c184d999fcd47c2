#ifndef MRATTLE_DRUDE_NOSE_HOOVER_INTEGRATOR_H_
#define MRATTLE_DRUDE_NOSE_HOOVER_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * Nose-Hoover dynamics for rigid bodies with Drude oscillators (the System's DrudeForce), with
 * the constructor and settings of OpenMM's DrudeNoseHooverIntegrator. The step is
 * MRattleNoseHooverIntegrator's (velocity Verlet with M-RATTLE between two half steps of the
 * thermostats) with two chains: one coupled to the kinetic energy KE_R of the Drude groups'
 * rigid motion and of every other particle (DrudeGroups: each body with the Drude particles
 * of its cores, each free core with its Drude particles), at the temperature, the other to
 * the kinetic energy KE_C of the Drude particles' motion relative to their cores (3 degrees
 * of freedom per Drude particle), at the Drude temperature. KE = KE_R + KE_C exactly; a half
 * step scales the rigid part of the velocities by the first chain's factor and the relative
 * part by the second's (docs/ALGORITHM.md).
 *
 * The dynamics is deterministic; kinetic + potential + computeHeatBathEnergy() (both chains)
 * is conserved up to the step's error while the hard wall does not act. Velocities are
 * on-step. Checkpoints and a State's integrator parameters hold both chains
 * (chainPositions, chainVelocities, drudeChainPositions, drudeChainVelocities). Drude
 * particles are never members of a body, and the hard wall (maxDrudeDistance, 0.02 nm by
 * default as OpenMM's) acts after the drift, as for MRattleDrudeLangevinIntegrator. Runs on
 * every platform (OpenCL and CUDA through the plugin's common device kernels, both chains on
 * the device).
 */
class OPENMM_EXPORT_MRATTLE MRattleDrudeNoseHooverIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param temperature              the temperature of the bodies and free particles, in Kelvin (finite and > 0)
     * @param collisionFrequency       the frequency of their chain's coupling, in inverse picoseconds (finite and >= 0)
     * @param drudeTemperature         the temperature of the Drude particles' motion relative to their cores, in Kelvin (finite and > 0)
     * @param drudeCollisionFrequency  the frequency of the Drude chain's coupling, in inverse picoseconds (finite and >= 0)
     * @param stepSize                 the step size, in picoseconds
     * @param chainLength              the number of thermostats in each chain (1 or more)
     * @param numMTS                   the number of sub-steps of each half step of the chains (1 or more)
     * @param numYoshidaSuzuki         the order of the Yoshida-Suzuki composition of a sub-step: 1, 3, 5 or 7
     */
    MRattleDrudeNoseHooverIntegrator(double temperature, double collisionFrequency, double drudeTemperature,
                                     double drudeCollisionFrequency, double stepSize, int chainLength = 3,
                                     int numMTS = 3, int numYoshidaSuzuki = 7);
    /** The temperature of the bodies' heat bath, in Kelvin. */
    double getTemperature() const {
        return temperature;
    }
    /** Set the temperature of the bodies' heat bath, in Kelvin (finite and > 0). */
    void setTemperature(double temperature);
    /** The collision frequency of the bodies' chain, in inverse picoseconds. */
    double getCollisionFrequency() const {
        return collisionFrequency;
    }
    /** Set the collision frequency of the bodies' chain, in inverse picoseconds (finite and >= 0). */
    void setCollisionFrequency(double frequency);
    /** The temperature of the Drude particles' relative motion, in Kelvin. */
    double getDrudeTemperature() const {
        return drudeTemperature;
    }
    /** Set the temperature of the Drude particles' relative motion, in Kelvin (finite and > 0). */
    void setDrudeTemperature(double temperature);
    /** The collision frequency of the Drude chain, in inverse picoseconds. */
    double getDrudeCollisionFrequency() const {
        return drudeCollisionFrequency;
    }
    /** Set the collision frequency of the Drude chain, in inverse picoseconds (finite and >= 0). */
    void setDrudeCollisionFrequency(double frequency);
    /** The hard wall's distance between a Drude particle and its core, in nm (0: no wall; 0.02 by default). */
    double getMaxDrudeDistance() const {
        return maxDrudeDistance;
    }
    /** Set the hard wall's distance, in nm (finite and >= 0; 0: no wall). */
    void setMaxDrudeDistance(double distance);
    /** The number of thermostats in each chain (fixed at construction). */
    int getChainLength() const {
        return chainLength;
    }
    /** The number of sub-steps of each half step of the chains (fixed at construction). */
    int getNumMultiTimeSteps() const {
        return numMTS;
    }
    /** The order of the Yoshida-Suzuki composition: 1, 3, 5 or 7 (fixed at construction). */
    int getNumYoshidaSuzukiTimeSteps() const {
        return numYoshidaSuzuki;
    }
    /**
     * The instantaneous temperature of the Drude particles' motion relative to their cores,
     * 2 KE_C / (3 n_drude k_B), in Kelvin (0 without Drude particles); KE_C is summed by the
     * platform (on the device on OpenCL and CUDA).
     */
    double computeDrudeTemperature();
    /**
     * The instantaneous temperature of everything else, 2 (KE - KE_C) / ((DOF - 3 n_drude)
     * k_B), in Kelvin (OpenMM's DrudeNoseHooverIntegrator::computeSystemTemperature).
     */
    double computeBodyTemperature();
    /**
     * RigidBodyIntegrator's draw at temperature, then each Drude particle's motion relative to
     * its core (KE_C) scaled to getDrudeTemperature(), as OpenMM's Drude integrators draw it.
     */
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(const OpenMM::System& system, double temperature,
                                                          int randomSeed) const override;
    /**
     * The energy of both heat baths, in kJ/mol: each chain's sum_j Q_j v_j^2 / 2 + N k_B T x_1
     * + k_B T sum_{j>1} x_j, with N = DOF - 3 n_drude and T the temperature for the bodies'
     * chain, N = 3 n_drude and T the Drude temperature for the Drude chain. Kinetic +
     * potential + this is the conserved quantity. Throws unless bound to a Context.
     */
    double computeHeatBathEnergy();

private:
    double temperature, collisionFrequency, drudeTemperature, drudeCollisionFrequency, maxDrudeDistance = 0.02;
    int chainLength, numMTS, numYoshidaSuzuki;
};

} // namespace MRattlePlugin

#endif
