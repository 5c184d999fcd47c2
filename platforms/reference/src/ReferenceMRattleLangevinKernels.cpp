#include "ReferenceMRattleLangevinKernels.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <random>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateMRattleLangevinStepKernel::initializeIntegrator(const System& system,
                                                                       const MRattleLangevinIntegrator& integrator) {
    dynamics.operations().seedRandom(integrator.getRandomNumberSeed());
}

void ReferenceIntegrateMRattleLangevinStepKernel::execute(ContextImpl& context, const MRattleLangevinIntegrator& integrator,
                                                          bool& forcesAreValid) {
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
        addNoise(friction, integrator.getTemperature(), h);
        dynamics.project(tolerance, false);
        dynamics.driftAndReset(0.0, 0.5 * h, tolerance);
    }
    dynamics.project(tolerance, false);
    dynamics.computeForces(context, integrator, forcesAreValid);
    dynamics.endStep(h, forcesAreValid);
}

void ReferenceIntegrateMRattleLangevinStepKernel::addNoise(double friction, double temperature, double h) {
    // Followed by RATTLE's velocity step: projected Gaussian noise is the noise on the rigid
    // degrees of freedom.
    vector<Vec3>& v = dynamics.velocities();
    const vector<double>& inverseMass = dynamics.operations().inverseMasses();
    std::mt19937_64& random = dynamics.operations().random();
    const double a = std::exp(-friction * h);
    const double kT = BOLTZ * temperature;
    std::normal_distribution<double> gaussian(0.0, 1.0);
    for (size_t i = 0; i < v.size(); i++)
        if (inverseMass[i] != 0) {
            const double sigma = std::sqrt((1 - a * a) * kT * inverseMass[i]);
            const double gx = gaussian(random), gy = gaussian(random), gz = gaussian(random);
            v[i] = v[i] * a + Vec3(gx, gy, gz) * sigma;
        }
}
