#include "CommonRigidBodyDynamics.h"
#include "CommonBodyForceInfo.h"
#include "CommonMRattleKernelSources.h"
#include "internal/FiniteValues.h"
#include "internal/ThermalVelocities.h"
#include "RigidBodyIntegrator.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

/** Connected groups of free constraints (union-find over their atoms). */
vector<vector<int> > constraintClusters(const System& system, const vector<int>& constraints) {
    std::map<int, int> parent;
    std::function<int(int)> root = [&](int atom) {
        while (parent[atom] != atom)
            atom = parent[atom] = parent[parent[atom]];
        return atom;
    };
    for (int c : constraints) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        if (!parent.count(p1))
            parent[p1] = p1;
        if (!parent.count(p2))
            parent[p2] = p2;
        parent[root(p1)] = root(p2);
    }
    std::map<int, vector<int> > byRoot;
    for (int c : constraints) {
        int p1, p2;
        double distance;
        system.getConstraintParameters(c, p1, p2, distance);
        byRoot[root(p1)].push_back(c);
    }
    vector<vector<int> > clusters;
    for (auto& entry : byRoot)
        clusters.push_back(entry.second);
    return clusters;
}

} // namespace

class CommonRigidBodyDynamics::ReorderListener : public ComputeContext::ReorderListener {
public:
    explicit ReorderListener(CommonRigidBodyDynamics& owner) : owner(owner) {
    }
    void execute() override {
        owner.mapAtoms();
        owner.atomsReordered = true;
        owner.stepFailure.atomsReordered();
    }

private:
    CommonRigidBodyDynamics& owner;
};

CommonRigidBodyDynamics::CommonRigidBodyDynamics(ComputeContext& cc, const std::string& integratorName)
    : cc(cc), stepFailure(cc, integratorName) {
}

CommonRigidBodyDynamics::~CommonRigidBodyDynamics() {
}

void CommonRigidBodyDynamics::initialize(const System& system, const RigidBodyTopology& topology) {
    // Whole bodies across reorderings: OpenMM builds its molecules once, when it initializes.
    cc.addForce(new CommonBodyForceInfo(topology.getBodies()));
    cc.initializeContexts();
    bodies = topology;
    numBodies = bodies.getNumBodies();
    shapeConstraints.reset(new BodyShapeConstraints(system, bodies));
    shapes.assign(numBodies, RigidBodyMath::Shape::General);
    inverseMasses.resize(system.getNumParticles());
    for (int i = 0; i < system.getNumParticles(); i++)
        inverseMasses[i] = (system.getParticleMass(i) == 0 ? 0.0 : 1.0 / system.getParticleMass(i));
    vector<int> starts = {0};
    for (int b = 0; b < numBodies; b++) {
        for (int atom : bodies.getBodyParticles(b))
            systemBodyAtoms.push_back(atom);
        starts.push_back(systemBodyAtoms.size());
    }
    vector<double> distances;
    vector<int> clusterStarts = {0}, clusterAtomStarts = {0};
    vector<bool> grouped(system.getNumParticles(), false);
    for (int atom : systemBodyAtoms)
        grouped[atom] = true;
    for (const vector<int>& cluster : constraintClusters(system, bodies.getFreeConstraints())) {
        for (int c : cluster) {
            int p1, p2;
            double distance;
            system.getConstraintParameters(c, p1, p2, distance);
            systemConstraintAtoms.push_back(p1);
            systemConstraintAtoms.push_back(p2);
            distances.push_back(distance);
            for (int atom : {p1, p2})
                if (!grouped[atom]) {
                    grouped[atom] = true;
                    systemClusterAtoms.push_back(atom);
                }
        }
        clusterStarts.push_back(distances.size());
        clusterAtomStarts.push_back(systemClusterAtoms.size());
    }
    numClusters = clusterStarts.size() - 1;
    // Every other particle moves alone (massless ones too: the step's backup holds them).
    for (int atom = 0; atom < system.getNumParticles(); atom++)
        if (!grouped[atom])
            systemFreeAtoms.push_back(atom);
    numFree = systemFreeAtoms.size();
    const bool doubleMixed = cc.getUseDoublePrecision() || cc.getUseMixedPrecision();
    const int mixedSize = doubleMixed ? sizeof(double) : sizeof(float);
    bodyStart.initialize<int>(cc, starts.size(), "mrattleBodyStart");
    bodyStart.upload(starts);
    bodyAtoms.initialize<int>(cc, std::max<size_t>(1, systemBodyAtoms.size()), "mrattleBodyAtoms");
    bodyShape.initialize<int>(cc, std::max(1, numBodies), "mrattleBodyShape");
    bodyShape.upload(vector<int>(std::max(1, numBodies), shapeCode(RigidBodyMath::Shape::General)));
    clusterStart.initialize<int>(cc, clusterStarts.size(), "mrattleClusterStart");
    clusterStart.upload(clusterStarts);
    constraintAtoms.initialize<mm_int2>(cc, std::max<size_t>(1, distances.size()), "mrattleConstraintAtoms");
    constraintDistance.initialize(cc, std::max<size_t>(1, distances.size()), mixedSize, "mrattleConstraintDistance");
    if (!distances.empty())
        constraintDistance.upload(distances, true);
    clusterAtomStart.initialize<int>(cc, clusterAtomStarts.size(), "mrattleClusterAtomStart");
    clusterAtomStart.upload(clusterAtomStarts);
    clusterAtoms.initialize<int>(cc, std::max<size_t>(1, systemClusterAtoms.size()), "mrattleClusterAtoms");
    freeAtoms.initialize<int>(cc, std::max<size_t>(1, systemFreeAtoms.size()), "mrattleFreeAtoms");
    bodyReference.initialize(cc, std::max<size_t>(1, systemBodyAtoms.size()),
                             doubleMixed ? sizeof(mm_double4) : sizeof(mm_float4), "mrattleBodyReference");
    bodyReference.upload(vector<mm_double4>(bodyReference.getSize(), mm_double4(0, 0, 0, 0)), true);
    bodyOrientation.initialize(cc, 9 * std::max(1, numBodies), mixedSize, "mrattleBodyOrientation");
    bodyOrientation.upload(identityOrientations(), true);
    velocityScaleArray.initialize(cc, 1, mixedSize, "mrattleVelocityScale");
    velocityScaleArray.upload(vector<double>(1, 1.0), true);
    stepFailure.initialize();
    mapAtoms();
    cc.addReorderListener(new ReorderListener(*this));
    bodyKineticEnergy.reset(new CommonBodyKineticEnergy(cc, numBodies, bodyStart, bodyAtoms));
    for (int f = 0; f < system.getNumForces(); f++)
        if (const AndersenThermostat* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f))) {
            hasAndersen = true;
            initRandomNumbers(thermostat->getRandomNumberSeed());
        }
    program = compileWith(hasAndersen ? CommonMRattleKernelSources::collisions : "");
    advanceGroups = program->createKernel("advanceGroups");
    projectBodies = program->createKernel("projectBodies");
    constrainFreeVelocities = program->createKernel("constrainFreeVelocities");
    if (hasAndersen)
        collideBodies = program->createKernel("collideBodies");
}

void CommonRigidBodyDynamics::initRandomNumbers(int seed) {
    cc.getIntegrationUtilities().initRandomNumberGenerator(seed);
    hasRandomNumbers = true;
}

void CommonRigidBodyDynamics::mapAtoms() {
    // cc.getAtomIndex()[i] is the System index of the atom the device holds at i.
    const vector<int>& order = cc.getAtomIndex();
    // A damaged checkpoint can hand OpenMM an order that is no permutation (it loads what it
    // reads): then map nothing, rather than write out of bounds; the Context must be set up
    // again before it steps (the integrator refuses until then).
    vector<int> deviceIndex(order.size(), -1);
    for (size_t i = 0; i < order.size(); i++) {
        if (order[i] < 0 || order[i] >= (int) order.size() || deviceIndex[order[i]] != -1)
            return;
        deviceIndex[order[i]] = i;
    }
    auto upload = [&](const vector<int>& systemAtoms, ComputeArray& array) {
        if (systemAtoms.empty())
            return;
        vector<int> atoms(systemAtoms.size());
        for (size_t k = 0; k < atoms.size(); k++)
            atoms[k] = deviceIndex[systemAtoms[k]];
        array.upload(atoms);
    };
    upload(systemBodyAtoms, bodyAtoms);
    upload(systemClusterAtoms, clusterAtoms);
    upload(systemFreeAtoms, freeAtoms);
    if (!systemConstraintAtoms.empty()) {
        vector<mm_int2> atoms(systemConstraintAtoms.size() / 2);
        for (size_t k = 0; k < atoms.size(); k++)
            atoms[k] = mm_int2(deviceIndex[systemConstraintAtoms[2 * k]], deviceIndex[systemConstraintAtoms[2 * k + 1]]);
        constraintAtoms.upload(atoms);
    }
}

void CommonRigidBodyDynamics::beginStep(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                        bool& forcesAreValid) {
    if (!argumentsSet)
        setKernelArguments();
    cc.getIntegrationUtilities().setNextStepSize(integrator.getStepSize());
    if (hasAndersen && numBodies > 0) {
        // The thermostat (updateContextState) re-drew single atoms: re-draw their whole bodies.
        IntegrationUtilities& integration = cc.getIntegrationUtilities();
        setMixedArg(collideBodies, collideKT, BOLTZ * context.getParameter(AndersenThermostat::Temperature()));
        collideBodies->setArg(collideRandomIndex, (unsigned int) integration.prepareRandomNumbers(cc.getPaddedNumAtoms()));
        collideBodies->execute(numBodies);
        project(integrator.getConstraintTolerance(), true);
    }
    // The step's first pass backs up the state (after the collisions: their velocities are
    // the step's start), with the step's index for the failure flag.
    backupStepIndex = stepFailure.stepStarted(context, integrator.getStepSize());
    tolerance = integrator.getConstraintTolerance();
    if (atomsReordered)
        forcesAreValid = false;  // computed for the atoms' old order
    atomsReordered = false;
    if (!forcesAreValid)
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
}

void CommonRigidBodyDynamics::advance(const Pass& pass) {
    if (!argumentsSet)
        setKernelArguments();
    const int numGroups = numBodies + numClusters + numFree;
    advanceGroups->setArg(advanceBackupIndex, backupStepIndex);
    setMixedArg(advanceGroups, advanceKickTime, pass.kickTime);
    advanceGroups->setArg(advanceProjectAfterKick, pass.projectAfterKick ? 1 : 0);
    setMixedArg(advanceGroups, advanceDriftTime, pass.driftTime);
    setMixedArg(advanceGroups, advanceTolerance, tolerance);
    setMixedArg(advanceGroups, advanceNoiseDecay, pass.noiseDecay);
    setMixedArg(advanceGroups, advanceNoiseScale, pass.noiseScale);
    if (pass.noiseScale != 0)
        advanceGroups->setArg(advanceRandomIndex,
                              (unsigned int) cc.getIntegrationUtilities().prepareRandomNumbers(cc.getPaddedNumAtoms()));
    advanceGroups->setArg(advanceProjectAtEnd, pass.projectAtEnd ? 1 : 0);
    advanceGroups->setArg(advanceResetFollows, pass.resetFollows ? 1 : 0);
    advanceGroups->setArg(advanceStepIndex, stepFailure.stepIndex());
    advanceGroups->setArg(advanceScaleVelocities, pass.scaleVelocities ? 1 : 0);
    if (numGroups > 0)
        advanceGroups->execute(numGroups);
    backupStepIndex = -1;  // once per step
}

void CommonRigidBodyDynamics::driftAndReset(double kickTime, double h, double tolerance) {
    this->tolerance = tolerance;
    Pass pass;
    pass.kickTime = kickTime;
    pass.driftTime = h;
    advance(pass);
}

void CommonRigidBodyDynamics::kick(double time) {
    Pass pass;
    pass.kickTime = time;
    advance(pass);
}

void CommonRigidBodyDynamics::project(double tolerance, bool onlyIfNotRigid) {
    if (!argumentsSet)
        setKernelArguments();
    if (backupStepIndex >= 0 && !onlyIfNotRigid) {
        this->tolerance = tolerance;
        Pass pass;  // the step's first pass: it backs up the state
        pass.projectAtEnd = true;
        advance(pass);
        return;
    }
    if (numBodies > 0) {
        projectBodies->setArg(projectOnlyIfNotRigid, onlyIfNotRigid ? 1 : 0);
        projectBodies->execute(numBodies);
    }
    if (numClusters > 0) {
        setMixedArg(constrainFreeVelocities, freeVelocitiesTolerance, tolerance);
        constrainFreeVelocities->setArg(freeVelocitiesStepIndex, stepFailure.stepIndex());
        constrainFreeVelocities->execute(numClusters);
    }
}

void CommonRigidBodyDynamics::computeForces(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                            bool& forcesAreValid) {
    cc.getIntegrationUtilities().computeVirtualSites();
    forcesAreValid = false;
    context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
}

void CommonRigidBodyDynamics::endStep(double stepSize, bool& forcesAreValid) {
    forcesAreValid = true;
    cc.setTime(cc.getTime() + stepSize);
    cc.setStepCount(cc.getStepCount() + 1);
    atomsReordered = false;
    cc.reorderAtoms();
    if (atomsReordered)
        forcesAreValid = false;
    stepFailure.stepQueued();
}

void CommonRigidBodyDynamics::finishSteps() {
    stepFailure.synchronize();
}

void CommonRigidBodyDynamics::projectVelocities(ContextImpl& context, double tolerance) {
    // Velocities are set from the host: checking them there costs one download per set.
    vector<Vec3> velocities;
    context.getVelocities(velocities);
    FiniteValues::require(velocities, "velocity");
    project(tolerance, true);
    vector<Vec3> projected;
    context.getVelocities(projected);
    try {
        FiniteValues::require(projected, "velocity projected at the current positions (a degenerate constraint?)");
    } catch (...) {
        context.setVelocities(velocities);
        throw;
    }
}

vector<Vec3> CommonRigidBodyDynamics::velocitiesForTemperature(ContextImpl& context, double temperature, int randomSeed,
                                                               double tolerance) {
    // Maxwell-Boltzmann per particle, projected on the device (bodies and free constraints),
    // then an exact rescale to the temperature with the rigid-body degrees of freedom.
    vector<Vec3> velocities = ThermalVelocities::maxwellBoltzmann(inverseMasses, temperature, randomSeed);
    context.setVelocities(velocities);
    project(tolerance, false);
    context.getVelocities(velocities);
    ThermalVelocities::scaleToTemperature(bodies, inverseMasses, bodies.getNumDegreesOfFreedom(bodyDegreesOfFreedom()),
                                           temperature, velocities);
    return velocities;
}

double CommonRigidBodyDynamics::kineticEnergy() {
    stepFailure.synchronize();
    return cc.getIntegrationUtilities().computeKineticEnergy(0.0);
}

void CommonRigidBodyDynamics::kineticEnergies(double& translational, double& rotational, double& free) {
    stepFailure.synchronize();
    bodyKineticEnergy->compute(translational, rotational, free);
}

int CommonRigidBodyDynamics::bodyDegreesOfFreedom() const {
    return RigidBodyTopology::getBodyDegreesOfFreedom(shapes);
}

