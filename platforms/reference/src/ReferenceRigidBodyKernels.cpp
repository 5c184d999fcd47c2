#include "ReferenceRigidBodyKernels.h"
#include "MRattleIntegrator.h"
#include "MRattleDrudeLangevinIntegrator.h"
#include "MRattleDrudeNoseHooverIntegrator.h"
#include "MRattleLangevinIntegrator.h"
#include "RigidSplittingIntegrator.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

// ---- MRattleIntegrator -------------------------------------------------------------------

void ReferenceIntegrateMRattleStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                     const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
}

void ReferenceIntegrateMRattleStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                  bool& forcesAreValid) {
    const MRattleIntegrator& integrator = static_cast<const MRattleIntegrator&>(bound);
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // Velocity Verlet: half kick, drift and reset, new forces, half kick and projection.
    state.beginStep(context, integrator, forcesAreValid);
    state.driftAndReset(0.5 * h, h, tolerance);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}

// ---- MRattleLangevinIntegrator -----------------------------------------------------------

void ReferenceIntegrateMRattleLangevinStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                             const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
    state.seedRandom(static_cast<const MRattleLangevinIntegrator&>(integrator).getRandomNumberSeed());
}

void ReferenceIntegrateMRattleLangevinStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                          bool& forcesAreValid) {
    const MRattleLangevinIntegrator& integrator = static_cast<const MRattleLangevinIntegrator&>(bound);
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction();
    // LangevinMiddle: kick and projection, half drift and reset, noise and projection, half
    // drift and reset, projection. The next step's beginStep computes the forces, after any
    // barostat move, as LangevinMiddleIntegrator does: one evaluation a step.
    state.beginStep(context, integrator, forcesAreValid);
    state.kick(h);
    state.project(tolerance);
    if (friction == 0)
        state.driftAndReset(0.0, h, tolerance);
    else {
        state.driftAndReset(0.0, 0.5 * h, tolerance);
        state.addNoise(friction, integrator.getTemperature(), h);
        state.project(tolerance);
        state.driftAndReset(0.0, 0.5 * h, tolerance);
    }
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}

// ---- the thermostats ---------------------------------------------------------------------

void ReferenceThermostatStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                            bool& forcesAreValid) {
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // The thermostat's half step, velocity Verlet (as MRattleIntegrator's), the thermostat's half step.
    state.beginStep(context, integrator, forcesAreValid);
    state.scaleVelocities(halfStepFactor(context, integrator));
    state.driftAndReset(0.5 * h, h, tolerance);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    state.scaleVelocities(halfStepFactor(context, integrator));
    state.endStep(h, forcesAreValid);
}

void ReferenceIntegrateMRattleNoseHooverStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                               const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
    chain = RigidBodyThermostats::NoseHooverChain(
        static_cast<const MRattleNoseHooverIntegrator&>(integrator).getChainLength());
    state.declareIntegratorState({{"chainPositions", &chain.positions}, {"chainVelocities", &chain.velocities}},
                                 true, false);
}

double ReferenceIntegrateMRattleNoseHooverStepKernel::halfStepFactor(ContextImpl& context,
                                                                     const RigidBodyIntegrator& bound) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(bound);
    return chain.propagate(state.computeKineticEnergy(context), state.getNumDegreesOfFreedom(),
                           BOLTZ * integrator.getTemperature(), integrator.getCollisionFrequency(),
                           0.5 * integrator.getStepSize(), integrator.getNumMultiTimeSteps(),
                           RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps()));
}

double ReferenceIntegrateMRattleNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                           const RigidBodyIntegrator& bound) {
    const MRattleNoseHooverIntegrator& integrator = static_cast<const MRattleNoseHooverIntegrator&>(bound);
    return chain.energy(state.getNumDegreesOfFreedom(), BOLTZ * integrator.getTemperature(),
                        integrator.getCollisionFrequency());
}

void ReferenceIntegrateMRattleBussiStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                          const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
    state.seedRandom(static_cast<const MRattleBussiIntegrator&>(integrator).getRandomNumberSeed());
    work = {0.0};
    state.declareIntegratorState({{"rescalingWork", &work}}, false, true);
}

double ReferenceIntegrateMRattleBussiStepKernel::halfStepFactor(ContextImpl& context, const RigidBodyIntegrator& bound) {
    const MRattleBussiIntegrator& integrator = static_cast<const MRattleBussiIntegrator&>(bound);
    const double kineticEnergy = state.computeKineticEnergy(context);
    const double scale = RigidBodyThermostats::csvrScale(kineticEnergy, state.getNumDegreesOfFreedom(),
                                                         BOLTZ * integrator.getTemperature(),
                                                         integrator.getCollisionFrequency(),
                                                         0.5 * integrator.getStepSize(), state.randomStream());
    work[0] += (scale * scale - 1) * kineticEnergy;
    return scale;
}

// ---- RigidSplittingIntegrator ------------------------------------------------------------

void ReferenceIntegrateRigidSplittingStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                            const RigidBodyIntegrator& integrator) {
    state.initialize(system, topology);
}

void ReferenceIntegrateRigidSplittingStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                         bool& forcesAreValid) {
    const RigidSplittingIntegrator& integrator = static_cast<const RigidSplittingIntegrator&>(bound);
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    // Velocity Verlet: half kick and the rotors' position step, new forces, half kick and projection.
    state.beginStep(context, integrator, forcesAreValid);
    state.rotorDriftAndReset(h, tolerance);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}

// ---- MRattleDrudeLangevinIntegrator ------------------------------------------------------

namespace {

/** KE_C of the groups at the Context's positions and velocities now. */
double drudeKineticEnergy(ContextImpl& context, const DrudeGroups& groups, int& numDrudeParticles) {
    const System& system = context.getSystem();
    vector<Vec3> x, v;
    context.getPositions(x);
    context.getVelocities(v);
    vector<double> masses(system.getNumParticles());
    for (int i = 0; i < system.getNumParticles(); i++)
        masses[i] = system.getParticleMass(i);
    numDrudeParticles = groups.getNumDrudeParticles();
    return groups.relativeKineticEnergy(x, v, masses);
}

} // namespace

double ReferenceIntegrateMRattleDrudeLangevinStepKernel::computeDrudeKineticEnergy(ContextImpl& context,
                                                                                   int& numDrudeParticles) {
    return drudeKineticEnergy(context, groups, numDrudeParticles);
}

void ReferenceIntegrateMRattleDrudeLangevinStepKernel::initialize(const System& system,
                                                                  const RigidBodyTopology& topology,
                                                                  const RigidBodyIntegrator& integrator) {
    groups = DrudeGroups(system, topology, IntegratorNames::MRattleDrudeLangevin.integrator);
    state.initialize(system, topology);
    state.seedRandom(static_cast<const MRattleDrudeLangevinIntegrator&>(integrator).getRandomNumberSeed());
}

void ReferenceIntegrateMRattleDrudeLangevinStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                               bool& forcesAreValid) {
    const MRattleDrudeLangevinIntegrator& integrator = static_cast<const MRattleDrudeLangevinIntegrator&>(bound);
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction(), drudeFriction = integrator.getDrudeFriction();
    DrudeGroups::requireNumDrudeParticles(context.getSystem(), groups.getNumDrudeParticles(),
                                          IntegratorNames::MRattleDrudeLangevin.integrator);
    // MRattleLangevinIntegrator's step with the split noise, then the hard wall after the drift
    // (the forces, as there, at the next step's start).
    state.beginStep(context, integrator, forcesAreValid);
    state.kick(h);
    state.project(tolerance);
    if (friction == 0 && drudeFriction == 0)
        state.driftAndReset(0.0, h, tolerance);
    else {
        state.driftAndReset(0.0, 0.5 * h, tolerance);
        state.addDrudeNoise(groups, friction, integrator.getTemperature(), drudeFriction,
                            integrator.getDrudeTemperature(), h);
        state.project(tolerance);
        state.driftAndReset(0.0, 0.5 * h, tolerance);
    }
    state.bounceDrudes(groups, integrator.getMaxDrudeDistance(), integrator.getDrudeTemperature(), h);
    state.project(tolerance);
    state.endStep(h, forcesAreValid);
}

// ---- MRattleDrudeNoseHooverIntegrator ----------------------------------------------------

void ReferenceIntegrateMRattleDrudeNoseHooverStepKernel::initialize(const System& system,
                                                                    const RigidBodyTopology& topology,
                                                                    const RigidBodyIntegrator& integrator) {
    groups = DrudeGroups(system, topology, IntegratorNames::MRattleDrudeNoseHoover.integrator);
    state.initialize(system, topology);
    const int length = static_cast<const MRattleDrudeNoseHooverIntegrator&>(integrator).getChainLength();
    chain = RigidBodyThermostats::NoseHooverChain(length);
    drudeChain = RigidBodyThermostats::NoseHooverChain(length);
    state.declareIntegratorState({{"chainPositions", &chain.positions},
                                  {"chainVelocities", &chain.velocities},
                                  {"drudeChainPositions", &drudeChain.positions},
                                  {"drudeChainVelocities", &drudeChain.velocities}},
                                 true, false);
}

void ReferenceIntegrateMRattleDrudeNoseHooverStepKernel::chainsHalfStep(const RigidBodyIntegrator& bound) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(bound);
    const double t = 0.5 * integrator.getStepSize();
    const int numMTS = integrator.getNumMultiTimeSteps();
    const std::vector<double> weights =
        RigidBodyThermostats::yoshidaSuzukiWeights(integrator.getNumYoshidaSuzukiTimeSteps());
    const int drudeDof = 3 * groups.getNumDrudeParticles(), dof = state.getNumDegreesOfFreedom() - drudeDof;
    // KE = KE_R + KE_C: each chain sees its own part; without Drude particles the Drude chain rests.
    double rigid, relative;
    state.computeDrudeKineticEnergies(groups, rigid, relative);
    const double factor = (dof > 0 ? chain.propagate(rigid, dof, BOLTZ * integrator.getTemperature(),
                                                     integrator.getCollisionFrequency(), t, numMTS, weights)
                                   : 1.0);
    const double drudeFactor =
        (drudeDof > 0 ? drudeChain.propagate(relative, drudeDof, BOLTZ * integrator.getDrudeTemperature(),
                                             integrator.getDrudeCollisionFrequency(), t, numMTS, weights)
                      : 1.0);
    state.scaleDrudeVelocities(groups, factor, drudeFactor);
}

void ReferenceIntegrateMRattleDrudeNoseHooverStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& bound,
                                                                 bool& forcesAreValid) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(bound);
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    DrudeGroups::requireNumDrudeParticles(context.getSystem(), groups.getNumDrudeParticles(),
                                          IntegratorNames::MRattleDrudeNoseHoover.integrator);
    // The chains' half step, velocity Verlet (MRattleIntegrator's) with the hard wall after
    // the drift, the chains' half step.
    state.beginStep(context, integrator, forcesAreValid);
    chainsHalfStep(integrator);
    state.driftAndReset(0.5 * h, h, tolerance);
    state.bounceDrudes(groups, integrator.getMaxDrudeDistance(), integrator.getDrudeTemperature(), h);
    state.computeForces(context, integrator, forcesAreValid);
    state.kick(0.5 * h);
    state.project(tolerance);
    chainsHalfStep(integrator);
    state.endStep(h, forcesAreValid);
}

double ReferenceIntegrateMRattleDrudeNoseHooverStepKernel::computeDrudeKineticEnergy(ContextImpl& context,
                                                                                     int& numDrudeParticles) {
    return drudeKineticEnergy(context, groups, numDrudeParticles);
}

double ReferenceIntegrateMRattleDrudeNoseHooverStepKernel::computeHeatBathEnergy(ContextImpl& context,
                                                                                 const RigidBodyIntegrator& bound) {
    const MRattleDrudeNoseHooverIntegrator& integrator = static_cast<const MRattleDrudeNoseHooverIntegrator&>(bound);
    const int drudeDof = 3 * groups.getNumDrudeParticles(), dof = state.getNumDegreesOfFreedom() - drudeDof;
    return chain.energy(dof, BOLTZ * integrator.getTemperature(), integrator.getCollisionFrequency()) +
           drudeChain.energy(drudeDof, BOLTZ * integrator.getDrudeTemperature(),
                             integrator.getDrudeCollisionFrequency());
}
