#ifndef MRATTLE_RIGID_BODY_STATE_H_
#define MRATTLE_RIGID_BODY_STATE_H_

#include "openmm/Vec3.h"
#include "internal/windowsExportMRattle.h"
#include <iosfwd>
#include <map>
#include <string>
#include <vector>

namespace OpenMM {
class ContextImpl;
}

namespace MRattlePlugin {

/**
 * An integrator's time-varying state as a State carries it (Context::getState() with the
 * integrator's parameters): named lists of numbers, e.g. a Nose-Hoover chain's positions.
 */
typedef std::map<std::string, std::vector<double> > IntegratorParameterValues;

/**
 * What the API asks of a platform's rigid-body state, whatever the integrator: one class per
 * platform implements it (ReferenceRigidBodyState, CommonRigidBodyState). The state owns the
 * bodies, their shapes, the step's phases and what a failed step puts back.
 */
class OPENMM_EXPORT_MRATTLE RigidBodyState {
public:
    virtual ~RigidBodyState();
    /** Positions were set: classify the bodies' shapes; throws naming a particle whose position is not finite. */
    virtual void updateShapes(OpenMM::ContextImpl& context) = 0;
    /**
     * Make the Context's velocities rigid (bodies projected, free constraints to tolerance);
     * rigid ones are kept bit for bit. Throws naming a particle whose velocity is not finite.
     */
    virtual void projectVelocities(OpenMM::ContextImpl& context, double tolerance) = 0;
    /** Maxwell-Boltzmann velocities projected onto the rigid degrees of freedom, at exactly this temperature. */
    virtual std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                                  int randomSeed, double tolerance) = 0;
    /** Sum of m v^2 / 2 over the Context's velocities. */
    virtual double computeKineticEnergy(OpenMM::ContextImpl& context) = 0;
    /** computeKineticEnergy() split into the bodies' translation, their rotation and the free particles. */
    virtual void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                        double& free) = 0;
    /** The end of a step(n) call: a platform that finds a failed step late puts back its start and throws now. */
    virtual void finishSteps(OpenMM::ContextImpl& context) = 0;
    /** Whether body number index is linear at the last positions set. */
    virtual bool isBodyLinear(int index) const = 0;
    /** The bodies' degrees of freedom at the last positions set: 6 each, 5 if linear, 3 if its atoms coincide. */
    virtual int getBodyDegreesOfFreedom() const = 0;
    /** Write the state's own data into a checkpoint, unframed (RigidBodyCheckpointHeader frames it). */
    virtual void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const = 0;
    /** Read what createCheckpoint() wrote; throws an OpenMMException saying what does not fit. */
    virtual void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) = 0;
    /** A refused checkpoint left OpenMM's part read unchecked: make what a later step could crash on valid. */
    virtual void discardRefusedCheckpoint(OpenMM::ContextImpl& context) = 0;
    /** The integrator's variables a State carries (a thermostat's; never a random stream). */
    virtual IntegratorParameterValues getIntegratorParameters(OpenMM::ContextImpl& context) = 0;
    /** Set what getIntegratorParameters() returns (names and sizes already checked). */
    virtual void setIntegratorParameters(OpenMM::ContextImpl& context, const IntegratorParameterValues& values) = 0;
};

/**
 * An integrator's own variables in a checkpoint, on every platform: their common length
 * first (int32) if lengthFirst (a Nose-Hoover chain's), then each one's values (doubles).
 */
OPENMM_EXPORT_MRATTLE void writeIntegratorVariables(std::ostream& stream,
                                                    const std::vector<const std::vector<double>*>& values,
                                                    bool lengthFirst);
/**
 * Read what writeIntegratorVariables() wrote into values, whose sizes say what is expected;
 * values change only if all of it fits, else an OpenMMException says what does not (names:
 * what the variables are called in messages).
 */
OPENMM_EXPORT_MRATTLE void readIntegratorVariables(std::istream& stream, const std::string& names,
                                                   const std::vector<std::vector<double>*>& values, bool lengthFirst);

} // namespace MRattlePlugin

#endif
