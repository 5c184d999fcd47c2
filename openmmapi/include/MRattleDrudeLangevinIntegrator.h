#ifndef MRATTLE_DRUDE_LANGEVIN_INTEGRATOR_H_
#define MRATTLE_DRUDE_LANGEVIN_INTEGRATOR_H_

#include "RigidBodyIntegrator.h"
#include "internal/windowsExportMRattle.h"

namespace MRattlePlugin {

/**
 * Langevin dynamics for rigid bodies with Drude oscillators (the System's DrudeForce), with
 * the constructor and settings of OpenMM's DrudeLangevinIntegrator. The step is
 * MRattleLangevinIntegrator's (LangevinMiddle with M-RATTLE); its noise step splits the
 * velocities of each body with the Drude particles of its cores, and of each free core with
 * its Drude particles, into the group's rigid motion with each Drude particle carried at its
 * core's velocity (translation for a free pair), coupled at the temperature with the friction,
 * and each Drude particle's motion relative to its core (zero total momentum), coupled at the
 * Drude temperature with the Drude friction (docs/ALGORITHM.md). For a free pair this is OpenMM's centre-of-mass and relative split.
 * Every other particle is at the temperature, as in MRattleLangevinIntegrator.
 *
 * Drude particles are never members of a body (a Context whose bodies hold one is refused,
 * naming it; declare the bodies with addRigidBody()); their cores may be. With a
 * maxDrudeDistance > 0, a Drude particle found farther than it from its core after the drift
 * bounces off the wall as in OpenMM's (a core in a body: the Drude particle alone moves); one
 * beyond twice the distance fails the step. Runs on every platform (OpenCL and CUDA through
 * the plugin's common device kernels).
 */
class OPENMM_EXPORT_MRATTLE MRattleDrudeLangevinIntegrator : public RigidBodyIntegrator {
public:
    /**
     * @param temperature         the temperature of the heat bath of the bodies and free particles, in Kelvin
     * @param frictionCoeff       the friction coefficient coupling them to it, in inverse picoseconds
     * @param drudeTemperature    the temperature of the Drude particles' motion relative to their cores, in Kelvin
     * @param drudeFrictionCoeff  the friction coefficient of that motion, in inverse picoseconds
     * @param stepSize            the step size, in picoseconds
     */
    MRattleDrudeLangevinIntegrator(double temperature, double frictionCoeff, double drudeTemperature,
                                   double drudeFrictionCoeff, double stepSize);
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
    /** The temperature of the Drude particles' relative motion, in Kelvin. */
    double getDrudeTemperature() const {
        return drudeTemperature;
    }
    /** Set the temperature of the Drude particles' relative motion, in Kelvin (finite and >= 0). */
    void setDrudeTemperature(double temperature);
    /** The friction coefficient of the Drude particles' relative motion, in inverse picoseconds. */
    double getDrudeFriction() const {
        return drudeFriction;
    }
    /** Set the friction coefficient of the Drude particles' relative motion, in inverse picoseconds (finite and >= 0). */
    void setDrudeFriction(double coeff);
    /** The hard wall's distance between a Drude particle and its core, in nm (0: no wall, the default). */
    double getMaxDrudeDistance() const {
        return maxDrudeDistance;
    }
    /** Set the hard wall's distance, in nm (finite and >= 0; 0: no wall). */
    void setMaxDrudeDistance(double distance);
    /** The seed of the random stream (0: a new one each time a Context is created). */
    int getRandomNumberSeed() const {
        return randomNumberSeed;
    }
    /** Set the seed of the random stream (as MRattleLangevinIntegrator's). */
    void setRandomNumberSeed(int seed) {
        randomNumberSeed = seed;
    }
    /**
     * The instantaneous temperature of the Drude particles' motion relative to their cores,
     * 2 KE_C / (3 n_drude k_B), in Kelvin, from the Context's positions and velocities (0
     * without Drude particles); KE_C is summed by the platform (on the device on OpenCL and CUDA).
     */
    double computeDrudeTemperature();
    /**
     * The instantaneous temperature of everything else, 2 (KE - KE_C) / ((DOF - 3 n_drude)
     * k_B), in Kelvin: the bodies' and free particles' temperature, which the heat bath holds
     * at getTemperature() (OpenMM 8's DrudeIntegrator::computeSystemTemperature).
     */
    double computeBodyTemperature();
    /**
     * RigidBodyIntegrator's draw at temperature, then each Drude particle's motion relative to
     * its core (KE_C) scaled to getDrudeTemperature(), as OpenMM's Drude integrators draw it.
     */
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(const OpenMM::System& system, double temperature,
                                                          int randomSeed) const override;

    /** The velocities are those of the middle of the step, as MRattleLangevinIntegrator's. */
    double getVelocityTimeOffset() const override {
        return getStepSize() / 2;
    }

private:
    double temperature, friction, drudeTemperature, drudeFriction, maxDrudeDistance = 0;
    int randomNumberSeed = 0;
};

} // namespace MRattlePlugin

#endif
