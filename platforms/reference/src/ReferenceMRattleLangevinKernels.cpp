#include "ReferenceMRattleLangevinKernels.h"
#include "MRattleLangevinIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateMRattleLangevinStepKernel::initialize(const System& system, const RigidBodyTopology& topology,
                                                            const RigidBodyIntegrator& integrator) {
    ReferenceRigidBodyStepKernel::initialize(system, topology, integrator);
    dynamics->seedRandom(static_cast<const MRattleLangevinIntegrator&>(integrator).getRandomNumberSeed());
}

void ReferenceIntegrateMRattleLangevinStepKernel::finishStep(ContextImpl& context, const MRattleLangevinIntegrator& integrator) {
    // Leapfrog: the next step's kick uses these forces; the velocities stay mid-step.
    ReferenceRigidBodyDynamics::advanceClock(context, integrator.getStepSize());
}

void ReferenceIntegrateMRattleLangevinStepKernel::integratePositions(ContextImpl& context,
                                                                    const MRattleLangevinIntegrator& integrator) {
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    const vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const vector<double>& inverseMass = dynamics->inverseMasses();
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const int n = x.size();
    // A full kick (leapfrog) and RATTLE's velocity step at the current positions.
    kicked.resize(n);
    dynamics->forEachParticleRange([&](int begin, int end) {
        for (int i = begin; i < end; i++)
            kicked[i] = (inverseMass[i] != 0 ? v[i] + f[i] * (h * inverseMass[i]) : v[i]);
    });
    dynamics->projectVelocities(x, kicked, tolerance);
    try {
        if (integrator.getFriction() == 0) {
            // No noise: the two half drifts are one, and the positions are M-RATTLE's.
            dynamics->driftAndReset(x, kicked, h, tolerance, newPositions, newVelocities);
        }
        else {
            middlePositions.resize(n);
            middleVelocities.resize(n);
            dynamics->driftAndReset(x, kicked, 0.5 * h, tolerance, middlePositions, middleVelocities);
            // Ornstein-Uhlenbeck over the whole step, then RATTLE's velocity step: projected
            // Gaussian noise is the noise on the rigid degrees of freedom.
            const double a = std::exp(-integrator.getFriction() * h);
            const double kT = BOLTZ * integrator.getTemperature();
            std::normal_distribution<double> gaussian(0.0, 1.0);
            for (int i = 0; i < n; i++)
                if (inverseMass[i] != 0) {
                    const double sigma = std::sqrt((1 - a * a) * kT * inverseMass[i]);
                    const double gx = gaussian(dynamics->random()), gy = gaussian(dynamics->random()),
                                 gz = gaussian(dynamics->random());
                    middleVelocities[i] = middleVelocities[i] * a + Vec3(gx, gy, gz) * sigma;
                }
            dynamics->projectVelocities(middlePositions, middleVelocities, tolerance);
            dynamics->driftAndReset(middlePositions, middleVelocities, 0.5 * h, tolerance, newPositions, newVelocities);
        }
        // The velocities kept are rigid at the new positions (the next kick's projection is
        // linear, so this changes no trajectory; it makes what the Context reports rigid).
        dynamics->projectVelocities(newPositions, newVelocities, tolerance);
    } catch (const OpenMMException& e) {
        throw OpenMMException(std::string("MRattleLangevinIntegrator: ") + e.what());
    }
    x.swap(newPositions);
    v.swap(newVelocities);
    placeVirtualSites(context);
}
