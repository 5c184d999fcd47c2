#include "CommonMRattleLangevinKernels.h"
#include "CommonKernelArguments.h"
#include "CommonMRattleKernelSources.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;

void CommonIntegrateMRattleLangevinStepKernel::initializeIntegrator(const System& system,
                                                                    const MRattleLangevinIntegrator& integrator) {
    ComputeContext& cc = dynamics.computeContext();
    // Now, not at the first step: OpenMM's checkpoints hold the device random state only
    // once the generator exists, so a new Context must have it before loading one.
    cc.getIntegrationUtilities().initRandomNumberGenerator(integrator.getRandomNumberSeed());
    program = dynamics.compileWith(CommonMRattleKernelSources::langevin);
    langevinNoise = program->createKernel("langevinNoise");
}

void CommonIntegrateMRattleLangevinStepKernel::execute(ContextImpl& context, const MRattleLangevinIntegrator& integrator,
                                                       bool& forcesAreValid) {
    ComputeContext& cc = dynamics.computeContext();
    ContextSelector selector(cc);
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    if (!argumentsSet) {
        CommonKernelArguments noise(langevinNoise, cc.getUseDoublePrecision() || cc.getUseMixedPrecision());
        noise.add(cc.getNumAtoms());
        noise.add(cc.getVelm());
        noiseDecay = noise.addMixed(1.0);
        noiseScale = noise.addMixed(0.0);
        noise.add(integration.getRandom());
        noiseRandomIndex = noise.add(0u);
        noise.add(dynamics.failureFlag());
        argumentsSet = true;
    }
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction();
    // LangevinMiddle: kick and projection, half drift and reset, noise and projection, half
    // drift and reset, projection, then the forces for the next step's kick.
    dynamics.beginStep(context, integrator, forcesAreValid);
    dynamics.kick(h);
    dynamics.project(tolerance, false);
    if (friction == 0)
        dynamics.driftAndReset(0.0, h, tolerance);
    else {
        dynamics.driftAndReset(0.0, 0.5 * h, tolerance);
        const double a = std::exp(-friction * h);
        dynamics.setMixedArg(langevinNoise, noiseDecay, a);
        dynamics.setMixedArg(langevinNoise, noiseScale, std::sqrt((1 - a * a) * BOLTZ * integrator.getTemperature()));
        langevinNoise->setArg(noiseRandomIndex, (unsigned int) integration.prepareRandomNumbers(cc.getPaddedNumAtoms()));
        langevinNoise->execute(cc.getNumAtoms());
        dynamics.project(tolerance, false);
        dynamics.driftAndReset(0.0, 0.5 * h, tolerance);
    }
    dynamics.project(tolerance, false);
    dynamics.computeForces(context, integrator, forcesAreValid);
    dynamics.endStep(h, forcesAreValid);
}
