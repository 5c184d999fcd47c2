#include "ReferenceRigidBodyDynamics.h"
#include "openmm/reference/ReferencePlatform.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

ReferencePlatform::PlatformData& platformData(ContextImpl& context) {
    // The CPU platform derives from the Reference platform and keeps this data too.
    return *reinterpret_cast<ReferencePlatform::PlatformData*>(context.getPlatformData());
}

} // namespace

ReferenceRigidBodyDynamics::ReferenceRigidBodyDynamics(const System& system, const RigidBodySet& bodies)
    : systemRef(&system), bodySet(&bodies) {
    const int n = system.getNumParticles();
    inverseMass.resize(n);
    for (int i = 0; i < n; i++) {
        double mass = system.getParticleMass(i);
        inverseMass[i] = (mass == 0.0 ? 0.0 : 1.0 / mass);
    }
    if (!bodies.getFreeConstraints().empty()) {
        // OpenMM's constraint code (CCMA, SETTLE for rigid water) on the free constraints only.
        System freeSystem;
        for (int i = 0; i < n; i++)
            freeSystem.addParticle(system.getParticleMass(i));
        for (int c : bodies.getFreeConstraints()) {
            int p1, p2;
            double distance;
            system.getConstraintParameters(c, p1, p2, distance);
            freeSystem.addConstraint(p1, p2, distance);
        }
        freeConstraints.reset(new ReferenceConstraints(freeSystem));
    }
}

vector<Vec3>& ReferenceRigidBodyDynamics::positions(ContextImpl& context) {
    return *platformData(context).positions;
}

vector<Vec3>& ReferenceRigidBodyDynamics::velocities(ContextImpl& context) {
    return *platformData(context).velocities;
}

vector<Vec3>& ReferenceRigidBodyDynamics::forces(ContextImpl& context) {
    return *platformData(context).forces;
}

void ReferenceRigidBodyDynamics::advanceClock(ContextImpl& context, double stepSize) {
    ReferencePlatform::PlatformData& data = platformData(context);
    data.time += stepSize;
    data.stepCount++;
}

void ReferenceRigidBodyDynamics::constrainFreePositions(vector<Vec3>& oldPositions, vector<Vec3>& newPositions,
                                                        double tolerance) {
    if (freeConstraints)
        freeConstraints->apply(oldPositions, newPositions, inverseMass, tolerance);
}

void ReferenceRigidBodyDynamics::projectVelocities(vector<Vec3>& positions, vector<Vec3>& velocities, double tolerance) {
    if (freeConstraints)
        freeConstraints->applyToVelocities(positions, velocities, inverseMass, tolerance);
    const double* x = coordinates(positions);
    double* v = coordinates(velocities);
    for (int b = 0; b < bodySet->getNumBodies(); b++)
        RigidBodyMath::projectBodyVelocities(bodySet->view(b), x, v);
}

void ReferenceRigidBodyDynamics::kickAndProject(ContextImpl& context, double stepSize, double tolerance) {
    vector<Vec3>& x = positions(context);
    vector<Vec3>& v = velocities(context);
    const vector<Vec3>& f = forces(context);
    const double halfStep = 0.5 * stepSize;
    for (size_t i = 0; i < v.size(); i++)
        if (inverseMass[i] != 0)
            v[i] += f[i] * (halfStep * inverseMass[i]);
    projectVelocities(x, v, tolerance);
    advanceClock(context, stepSize);
}

double ReferenceRigidBodyDynamics::kineticEnergy(const vector<Vec3>& velocities) const {
    double energy = 0;
    for (size_t i = 0; i < velocities.size(); i++)
        if (inverseMass[i] != 0)
            energy += 0.5 * velocities[i].dot(velocities[i]) / inverseMass[i];
    return energy;
}
