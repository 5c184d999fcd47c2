#include "ReferenceRigidSplittingKernels.h"
#include "RigidSplittingIntegrator.h"
#include "mrattle/RigidBodyRotor.h"
#include "openmm/reference/ReferenceVirtualSites.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void ReferenceIntegrateRigidSplittingStepKernel::initialize(const System& system, const RigidBodySet& bodies) {
    dynamics.reset(new ReferenceRigidBodyDynamics(system, bodies));
    newPositions.resize(system.getNumParticles());
    newVelocities.resize(system.getNumParticles());
}

void ReferenceIntegrateRigidSplittingStepKernel::projectVelocities(ContextImpl& context, vector<Vec3>& velocities,
                                                                  double tolerance) {
    dynamics->projectVelocities(ReferenceRigidBodyDynamics::positions(context), velocities, tolerance);
}

void ReferenceIntegrateRigidSplittingStepKernel::projectContextVelocities(ContextImpl& context, double tolerance) {
    projectVelocities(context, ReferenceRigidBodyDynamics::velocities(context), tolerance);
}

double ReferenceIntegrateRigidSplittingStepKernel::computeKineticEnergy(ContextImpl& context) {
    return dynamics->kineticEnergy(ReferenceRigidBodyDynamics::velocities(context));
}

void ReferenceIntegrateRigidSplittingStepKernel::integratePositions(ContextImpl& context,
                                                                   const RigidSplittingIntegrator& integrator) {
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const vector<double>& inverseMass = dynamics->inverseMasses();
    const RigidBodySet& bodies = dynamics->bodies();
    const double h = integrator.getStepSize();
    const int n = x.size();

    // Free particles: half kick and drift, then RATTLE for their constraints (body atoms
    // are overwritten below; they take no part in free constraints).
    for (int i = 0; i < n; i++)
        newPositions[i] = (inverseMass[i] != 0 ? x[i] + (v[i] + f[i] * (0.5 * h * inverseMass[i])) * h : x[i]);
    dynamics->constrainFreePositions(x, newPositions, integrator.getConstraintTolerance());
    for (int b = 0; b < bodies.getNumBodies(); b++)
        RigidBodyRotor::positionStep(bodies.view(b), coordinates(x), coordinates(v), coordinates(f), h,
                                     coordinates(newPositions), coordinates(newVelocities));
    const double inverseStep = 1.0 / h;
    for (int i = 0; i < n; i++) {
        if (inverseMass[i] != 0) {
            v[i] = (bodies.getBodyOfParticle(i) < 0 ? (newPositions[i] - x[i]) * inverseStep : newVelocities[i]);
            x[i] = newPositions[i];
        }
    }
    ReferenceVirtualSites::computePositions(dynamics->system(), x);
}

void ReferenceIntegrateRigidSplittingStepKernel::integrateVelocities(ContextImpl& context,
                                                                    const RigidSplittingIntegrator& integrator) {
    // The second half kick of momentum and angular momentum is exactly a Cartesian half
    // kick followed by the rigid-body projection at the new positions (as in M-RATTLE).
    vector<Vec3>& x = ReferenceRigidBodyDynamics::positions(context);
    vector<Vec3>& v = ReferenceRigidBodyDynamics::velocities(context);
    const vector<Vec3>& f = ReferenceRigidBodyDynamics::forces(context);
    const vector<double>& inverseMass = dynamics->inverseMasses();
    const double halfStep = 0.5 * integrator.getStepSize();
    for (size_t i = 0; i < v.size(); i++)
        if (inverseMass[i] != 0)
            v[i] += f[i] * (halfStep * inverseMass[i]);
    dynamics->projectVelocities(x, v, integrator.getConstraintTolerance());
    ReferenceRigidBodyDynamics::advanceClock(context, integrator.getStepSize());
}
