#include "CommonMRattleLangevinKernels.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;

void CommonIntegrateMRattleLangevinStepKernel::initializeIntegrator(const System& system,
                                                                    const MRattleLangevinIntegrator& integrator) {
    // Now, not at the first step: OpenMM's checkpoints hold the device random state only
    // once the generator exists, so a new Context must have it before loading one. OpenMM
    // has one device generator: with an AndersenThermostat it already has that one's seed.
    if (!dynamics.hasAndersenThermostat())
        dynamics.initRandomNumbers(integrator.getRandomNumberSeed());
}

void CommonIntegrateMRattleLangevinStepKernel::execute(ContextImpl& context, const MRattleLangevinIntegrator& integrator,
                                                       bool& forcesAreValid) {
    ContextSelector selector(dynamics.computeContext());
    const double h = integrator.getStepSize(), friction = integrator.getFriction();
    // LangevinMiddle: kick and projection, half drift and reset, noise and projection (one
    // pass), half drift and reset and projection (a second), then the forces for the next
    // step's kick. Without friction: kick, projection, drift, projection in one pass.
    dynamics.beginStep(context, integrator, forcesAreValid);
    CommonRigidBodyDynamics::Pass first;
    first.kickTime = h;
    first.projectAfterKick = true;
    if (friction == 0) {
        first.driftTime = h;
        first.projectAtEnd = true;
        dynamics.advance(first);
    }
    else {
        const double a = std::exp(-friction * h);
        first.driftTime = 0.5 * h;
        first.noiseDecay = a;
        first.noiseScale = std::sqrt((1 - a * a) * BOLTZ * integrator.getTemperature());
        first.resetFollows = true;
        dynamics.advance(first);
        CommonRigidBodyDynamics::Pass second;
        second.driftTime = 0.5 * h;
        second.projectAtEnd = true;
        dynamics.advance(second);
    }
    dynamics.computeForces(context, integrator, forcesAreValid);
    dynamics.endStep(h, forcesAreValid);
}
