#include "CommonMRattleKernels.h"
#include "CommonMRattleKernelSources.h"
#include "MRattleLangevinIntegrator.h"
#include "RigidBodyIntegrator.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <cstdint>
#include <map>
#include <numeric>
#include <random>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

/** Steps between reads of the device's failure flag (each read waits for the device). */
const int FailureCheckInterval = 100;

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

/** Throw naming the first particle whose value is not finite. */
void requireFinite(const vector<Vec3>& values, const char* what) {
    for (size_t i = 0; i < values.size(); i++)
        if (!std::isfinite(values[i][0] + values[i][1] + values[i][2]))
            throw OpenMMException(std::string("the ") + what + " of particle " + std::to_string(i) + " is not finite");
}

} // namespace

class CommonIntegrateMRattleStepKernel::ReorderListener : public ComputeContext::ReorderListener {
public:
    explicit ReorderListener(CommonIntegrateMRattleStepKernel& owner) : owner(owner) {
    }
    void execute() override {
        owner.mapAtoms();
    }

private:
    CommonIntegrateMRattleStepKernel& owner;
};

CommonIntegrateMRattleStepKernel::~CommonIntegrateMRattleStepKernel() {
}

void CommonIntegrateMRattleStepKernel::initialize(const System& system, const RigidBodyTopology& bodies,
                                                  const RigidBodyIntegrator& integrator) {
    cc.initializeContexts();
    ContextSelector selector(cc);
    const MRattleLangevinIntegrator* langevinIntegrator = dynamic_cast<const MRattleLangevinIntegrator*>(&integrator);
    langevin = (langevinIntegrator != nullptr);
    topology = bodies;
    numBodies = topology.getNumBodies();
    shapeConstraints.reset(new BodyShapeConstraints(system, topology));
    shapes.assign(numBodies, RigidBodyMath::Shape::General);
    vector<int> starts = {0};
    for (int b = 0; b < numBodies; b++) {
        for (int atom : topology.getBodyParticles(b))
            systemBodyAtoms.push_back(atom);
        starts.push_back(systemBodyAtoms.size());
    }
    vector<vector<int> > clusters = constraintClusters(system, topology.getFreeConstraints());
    numClusters = clusters.size();
    vector<int> clusterStarts = {0};
    for (const vector<int>& cluster : clusters) {
        for (int c : cluster) {
            int p1, p2;
            double distance;
            system.getConstraintParameters(c, p1, p2, distance);
            systemConstraintAtoms.push_back(p1);
            systemConstraintAtoms.push_back(p2);
            constraintDistances.push_back(distance);
        }
        clusterStarts.push_back(constraintDistances.size());
    }
    const bool doubleMixed = cc.getUseDoublePrecision() || cc.getUseMixedPrecision();
    const int mixedSize = doubleMixed ? sizeof(double) : sizeof(float);
    bodyStart.initialize<int>(cc, starts.size(), "mrattleBodyStart");
    bodyStart.upload(starts);
    bodyAtoms.initialize<int>(cc, std::max<size_t>(1, systemBodyAtoms.size()), "mrattleBodyAtoms");
    bodyLinear.initialize<int>(cc, std::max(1, numBodies), "mrattleBodyLinear");
    bodyLinear.upload(vector<int>(std::max(1, numBodies), 0));
    clusterStart.initialize<int>(cc, clusterStarts.size(), "mrattleClusterStart");
    clusterStart.upload(clusterStarts);
    constraintAtoms.initialize<mm_int2>(cc, std::max<size_t>(1, constraintDistances.size()), "mrattleConstraintAtoms");
    constraintDistance.initialize(cc, std::max<size_t>(1, constraintDistances.size()), mixedSize, "mrattleConstraintDistance");
    if (!constraintDistances.empty())
        constraintDistance.upload(constraintDistances, true);
    newVelocity.initialize(cc, cc.getPaddedNumAtoms(), doubleMixed ? sizeof(mm_double4) : sizeof(mm_float4),
                           "mrattleNewVelocity");
    failure.initialize<int>(cc, 1, "mrattleFailure");
    failure.upload(vector<int>(1, 0));
    mapAtoms();
    cc.addReorderListener(new ReorderListener(*this));
    bodyKineticEnergy.reset(new CommonBodyKineticEnergy(cc, numBodies, bodyStart, bodyAtoms));

    for (int f = 0; f < system.getNumForces(); f++)
        if (const AndersenThermostat* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f))) {
            hasAndersen = true;
            cc.getIntegrationUtilities().initRandomNumberGenerator(thermostat->getRandomNumberSeed());
        }
    if (langevin) {
        // Now, not at the first step: OpenMM's checkpoints hold the device random state only
        // once the generator exists, so a new Context must have it before loading one.
        cc.getIntegrationUtilities().initRandomNumberGenerator(langevinIntegrator->getRandomNumberSeed());
        const int vectorSize = doubleMixed ? sizeof(mm_double4) : sizeof(mm_float4);
        posqBackup.initialize(cc, cc.getPaddedNumAtoms(), cc.getPosq().getElementSize(), "mrattlePosqBackup");
        // Only mixed precision has position corrections; the kernel still needs an argument.
        correctionBackup.initialize(cc, cc.getUseMixedPrecision() ? cc.getPaddedNumAtoms() : 1,
                                    cc.getPosq().getElementSize(), "mrattleCorrectionBackup");
        velmBackup.initialize(cc, cc.getPaddedNumAtoms(), vectorSize, "mrattleVelmBackup");
    }
    std::map<std::string, std::string> defines;
    if (doubleMixed)
        defines["USE_DOUBLE_MIXED"] = "1";
    ComputeProgram program = cc.compileProgram(CommonMRattleKernelSources::mrattle, defines);
    kickAndDrift = program->createKernel("kickAndDrift");
    resetBodies = program->createKernel("resetBodies");
    constrainFreePositions = program->createKernel("constrainFreePositions");
    applyPositionStep = program->createKernel("applyPositionStep");
    kickVelocities = program->createKernel("kickVelocities");
    projectBodies = program->createKernel("projectBodies");
    constrainFreeVelocities = program->createKernel("constrainFreeVelocities");
    if (langevin) {
        langevinNoise = program->createKernel("langevinNoise");
        backupState = program->createKernel("backupState");
    }
}

void CommonIntegrateMRattleStepKernel::mapAtoms() {
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
    if (!systemBodyAtoms.empty()) {
        vector<int> atoms(systemBodyAtoms.size());
        for (size_t k = 0; k < atoms.size(); k++)
            atoms[k] = deviceIndex[systemBodyAtoms[k]];
        bodyAtoms.upload(atoms);
    }
    if (!systemConstraintAtoms.empty()) {
        vector<mm_int2> atoms(systemConstraintAtoms.size() / 2);
        for (size_t k = 0; k < atoms.size(); k++)
            atoms[k] = mm_int2(deviceIndex[systemConstraintAtoms[2 * k]], deviceIndex[systemConstraintAtoms[2 * k + 1]]);
        constraintAtoms.upload(atoms);
    }
}

void CommonIntegrateMRattleStepKernel::setKernelArguments() {
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    const int numAtoms = cc.getNumAtoms(), padded = cc.getPaddedNumAtoms();
    const bool doubleMixed = cc.getUseDoublePrecision() || cc.getUseMixedPrecision();
    auto addMixed = [&](ComputeKernel& kernel, double value) {
        if (doubleMixed)
            kernel->addArg(value);
        else
            kernel->addArg((float) value);
    };
    kickAndDrift->addArg(numAtoms);
    kickAndDrift->addArg(padded);
    addMixed(kickAndDrift, 0.0);  // 2: kick time
    addMixed(kickAndDrift, 0.0);  // 3: drift time
    kickAndDrift->addArg(cc.getVelm());
    kickAndDrift->addArg(cc.getLongForceBuffer());
    kickAndDrift->addArg(integration.getPosDelta());
    kickAndDrift->addArg(newVelocity);
    kickAndDrift->addArg(failure);
    kickAndDrift->addArg(0);  // 9: the step

    resetBodies->addArg(numBodies);
    resetBodies->addArg(bodyStart);
    resetBodies->addArg(bodyAtoms);
    resetBodies->addArg(bodyLinear);
    addMixed(resetBodies, 0.0);  // 4: drift time
    resetBodies->addArg(cc.getPosq());
    resetBodies->addArg(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    resetBodies->addArg(integration.getPosDelta());
    resetBodies->addArg(newVelocity);
    resetBodies->addArg(failure);
    resetBodies->addArg(0);  // 10: the step

    constrainFreePositions->addArg(numClusters);
    constrainFreePositions->addArg(clusterStart);
    constrainFreePositions->addArg(constraintAtoms);
    constrainFreePositions->addArg(constraintDistance);
    addMixed(constrainFreePositions, 0.0);  // 4: drift time
    constrainFreePositions->addArg(cc.getPosq());
    constrainFreePositions->addArg(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    constrainFreePositions->addArg(integration.getPosDelta());
    constrainFreePositions->addArg(newVelocity);
    addMixed(constrainFreePositions, 1e-5);  // 9: the tolerance
    constrainFreePositions->addArg(failure);
    constrainFreePositions->addArg(0);  // 11: the step

    applyPositionStep->addArg(numAtoms);
    applyPositionStep->addArg(cc.getPosq());
    applyPositionStep->addArg(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    applyPositionStep->addArg(cc.getVelm());
    applyPositionStep->addArg(integration.getPosDelta());
    applyPositionStep->addArg(newVelocity);
    applyPositionStep->addArg(failure);

    kickVelocities->addArg(numAtoms);
    kickVelocities->addArg(padded);
    addMixed(kickVelocities, 0.0);  // 2: kick time
    kickVelocities->addArg(cc.getVelm());
    kickVelocities->addArg(cc.getLongForceBuffer());
    kickVelocities->addArg(failure);

    projectBodies->addArg(numBodies);
    projectBodies->addArg(bodyStart);
    projectBodies->addArg(bodyAtoms);
    projectBodies->addArg(bodyLinear);
    projectBodies->addArg(cc.getPosq());
    projectBodies->addArg(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    projectBodies->addArg(cc.getVelm());
    projectBodies->addArg(0);  // 7: onlyIfNotRigid
    projectBodies->addArg(failure);
    projectBodies->addArg(0);  // 9: collide
    addMixed(projectBodies, 0.0);  // 10: kT
    if (hasAndersen)
        projectBodies->addArg(integration.getRandom());
    else
        projectBodies->addArg(failure);  // 11: never read without collisions
    projectBodies->addArg(0u);  // 12: random index

    constrainFreeVelocities->addArg(numClusters);
    constrainFreeVelocities->addArg(clusterStart);
    constrainFreeVelocities->addArg(constraintAtoms);
    constrainFreeVelocities->addArg(cc.getPosq());
    constrainFreeVelocities->addArg(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
    constrainFreeVelocities->addArg(cc.getVelm());
    addMixed(constrainFreeVelocities, 1e-5);  // 6: the tolerance
    constrainFreeVelocities->addArg(failure);
    constrainFreeVelocities->addArg(0);  // 8: the step

    if (langevin) {  // the Langevin kernels are launched only by a Langevin step
        langevinNoise->addArg(numAtoms);
        langevinNoise->addArg(cc.getVelm());
        addMixed(langevinNoise, 1.0);  // 2: a = exp(-friction h)
        addMixed(langevinNoise, 0.0);  // 3: sqrt((1 - a^2) kT)
        langevinNoise->addArg(integration.getRandom());
        langevinNoise->addArg(0u);  // 5: random index
        langevinNoise->addArg(failure);
        backupState->addArg(numAtoms);
        backupState->addArg(cc.getPosq());
        backupState->addArg(cc.getUseMixedPrecision() ? cc.getPosqCorrection() : cc.getPosq());
        backupState->addArg(cc.getVelm());
        backupState->addArg(posqBackup);
        backupState->addArg(correctionBackup);
        backupState->addArg(velmBackup);
        backupState->addArg(failure);
    }
    argumentsSet = true;
}

void CommonIntegrateMRattleStepKernel::project(double tolerance, bool onlyIfNotRigid, bool collide, double kT) {
    if (!argumentsSet)
        setKernelArguments();
    if (numBodies > 0) {
        projectBodies->setArg(7, onlyIfNotRigid ? 1 : 0);
        projectBodies->setArg(9, collide ? 1 : 0);
        setMixedArg(projectBodies, 10, kT);
        if (collide)
            projectBodies->setArg(12, (unsigned int) cc.getIntegrationUtilities().prepareRandomNumbers(cc.getPaddedNumAtoms()));
        projectBodies->execute(numBodies);
    }
    if (numClusters > 0) {
        setMixedArg(constrainFreeVelocities, 6, tolerance);
        constrainFreeVelocities->setArg(8, (int) cc.getStepCount());
        constrainFreeVelocities->execute(numClusters);
    }
}

void CommonIntegrateMRattleStepKernel::setMixedArg(ComputeKernel& kernel, int index, double value) {
    if (cc.getUseDoublePrecision() || cc.getUseMixedPrecision())
        kernel->setArg(index, value);
    else
        kernel->setArg(index, (float) value);
}

void CommonIntegrateMRattleStepKernel::driftAndReset(double kickTime, double h, double tolerance, int step) {
    const int numAtoms = cc.getNumAtoms();
    setMixedArg(kickAndDrift, 2, kickTime);
    setMixedArg(kickAndDrift, 3, h);
    kickAndDrift->setArg(9, step);
    kickAndDrift->execute(numAtoms);
    if (numBodies > 0) {
        setMixedArg(resetBodies, 4, h);
        resetBodies->setArg(10, step);
        resetBodies->execute(numBodies);
    }
    if (numClusters > 0) {
        setMixedArg(constrainFreePositions, 4, h);
        setMixedArg(constrainFreePositions, 9, tolerance);
        constrainFreePositions->setArg(11, step);
        constrainFreePositions->execute(numClusters);
    }
    applyPositionStep->execute(numAtoms);
}

void CommonIntegrateMRattleStepKernel::kick(double kickTime) {
    setMixedArg(kickVelocities, 2, kickTime);
    kickVelocities->execute(cc.getNumAtoms());
}

void CommonIntegrateMRattleStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                               bool& forcesAreValid) {
    ContextSelector selector(cc);
    if (!argumentsSet)
        setKernelArguments();
    IntegrationUtilities& integration = cc.getIntegrationUtilities();
    const double h = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const int step = (int) cc.getStepCount();
    integration.setNextStepSize(h);
    if (hasAndersen)
        project(tolerance, true, true, BOLTZ * context.getParameter(AndersenThermostat::Temperature()));
    if (!forcesAreValid)
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    if (!langevin) {
        // Velocity Verlet: half kick, drift and reset, new forces, half kick and projection.
        driftAndReset(0.5 * h, h, tolerance, step);
        integration.computeVirtualSites();
        forcesAreValid = false;
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
        kick(0.5 * h);
        project(tolerance, false, false, 0.0);
    }
    else {
        // LangevinMiddle: kick and projection, half drift and reset, noise and projection,
        // half drift and reset, projection; the state is backed up first, because it is
        // written in the middle of the step and a failure must leave the state before it.
        const MRattleLangevinIntegrator& settings = dynamic_cast<const MRattleLangevinIntegrator&>(integrator);
        backupState->execute(cc.getNumAtoms());
        kick(h);
        project(tolerance, false, false, 0.0);
        const double friction = settings.getFriction();
        if (friction == 0)
            driftAndReset(0.0, h, tolerance, step);
        else {
            driftAndReset(0.0, 0.5 * h, tolerance, step);
            const double a = std::exp(-friction * h);
            setMixedArg(langevinNoise, 2, a);
            setMixedArg(langevinNoise, 3, std::sqrt((1 - a * a) * BOLTZ * settings.getTemperature()));
            langevinNoise->setArg(5, (unsigned int) integration.prepareRandomNumbers(cc.getPaddedNumAtoms()));
            langevinNoise->execute(cc.getNumAtoms());
            project(tolerance, false, false, 0.0);
            driftAndReset(0.0, 0.5 * h, tolerance, step);
        }
        project(tolerance, false, false, 0.0);
        integration.computeVirtualSites();
        forcesAreValid = false;
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    }
    forcesAreValid = true;
    cc.setTime(cc.getTime() + h);
    cc.setStepCount(cc.getStepCount() + 1);
    cc.reorderAtoms();
    if (++stepsSinceFailureCheck >= FailureCheckInterval)
        checkFailure();
}

void CommonIntegrateMRattleStepKernel::checkFailure() {
    stepsSinceFailureCheck = 0;
    int value = 0;
    failure.download(&value);
    if (value == 0)
        return;
    // The device has done nothing since the failed step: put the clock back to it.
    const long long failedStep = value - 1;
    const double h = cc.getIntegrationUtilities().getLastStepSize();
    if (langevin) {
        // The Langevin step writes the state in its middle: put back the copy from its start.
        posqBackup.copyTo(cc.getPosq());
        if (cc.getUseMixedPrecision())
            correctionBackup.copyTo(cc.getPosqCorrection());
        velmBackup.copyTo(cc.getVelm());
    }
    cc.setTime(cc.getTime() - (cc.getStepCount() - failedStep) * h);
    cc.setStepCount(failedStep);
    failure.upload(vector<int>(1, 0));
    throw OpenMMException("MRattleIntegrator: at step " + std::to_string(failedStep) +
                          " the position reset of a rigid body found no rotation, the free-particle constraints did not "
                          "converge, or a velocity was not finite; the step size is too large for the forces, or they "
                          "are not finite. The "
                          "Context holds the state from before that step.");
}

void CommonIntegrateMRattleStepKernel::updateShapes(ContextImpl& context) {
    ContextSelector selector(cc);
    checkFailure();
    // Positions were just uploaded from the host: classify on the host with the core.
    vector<Vec3> positions;
    context.getPositions(positions);
    requireFinite(positions, "position");
    if (shapeConstraints->apply(positions)) {
        // Back to the device (this notifies the integrator again, which then finds every
        // body on its geometry).
        context.setPositions(positions);
        return;
    }
    const double* x = reinterpret_cast<const double*>(positions.data());
    vector<int> flags(std::max(1, numBodies), 0);
    for (int b = 0; b < numBodies; b++) {
        const vector<int>& atoms = topology.getBodyParticles(b);
        RigidBodyMath::BodyView body{atoms.data(), (int) atoms.size(), topology.getMasses().data(),
                                     topology.getBodyMass(b), false};
        Eigen::Vector3d center = RigidBodyMath::centerOfMass(body, x);
        shapes[b] = RigidBodyMath::classifyShape(RigidBodyMath::secondMoment(body, x, center), body.totalMass);
        flags[b] = (shapes[b] != RigidBodyMath::Shape::General);  // a point takes the linear arithmetic
    }
    bodyLinear.upload(flags);
}

void CommonIntegrateMRattleStepKernel::projectVelocities(ContextImpl& context, double tolerance) {
    ContextSelector selector(cc);
    checkFailure();
    // Velocities are set from the host: checking them there costs one download per set.
    vector<Vec3> velocities;
    context.getVelocities(velocities);
    requireFinite(velocities, "velocity");
    project(tolerance, true, false, 0.0);
    // The integrator then refuses to step until finite velocities are set.
    vector<Vec3> projected;
    context.getVelocities(projected);
    requireFinite(projected, "velocity projected at the current positions (a degenerate constraint?)");
}

vector<Vec3> CommonIntegrateMRattleStepKernel::getVelocitiesForTemperature(ContextImpl& context, double temperature,
                                                                           int randomSeed, double tolerance) {
    ContextSelector selector(cc);
    checkFailure();
    // Maxwell-Boltzmann per particle, projected on the device (bodies and free constraints),
    // then an exact rescale to the temperature with the rigid-body degrees of freedom.
    const vector<double>& masses = topology.getMasses();
    const int numParticles = masses.size();
    std::mt19937_64 generator(randomSeed);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    vector<Vec3> velocities(numParticles);
    for (int i = 0; i < numParticles; i++)
        if (masses[i] != 0) {
            double scale = std::sqrt(BOLTZ * temperature / masses[i]);
            double x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
            velocities[i] = Vec3(x, y, z) * scale;
        }
    context.setVelocities(velocities);
    project(tolerance, false, false, 0.0);
    context.getVelocities(velocities);
    double totalMass = 0, kinetic = 0;
    Vec3 momentum;
    for (int i = 0; i < numParticles; i++) {
        totalMass += masses[i];
        momentum += velocities[i] * masses[i];
    }
    if (topology.removesCenterOfMassMotion() && totalMass > 0)
        for (int i = 0; i < numParticles; i++)
            if (masses[i] != 0)
                velocities[i] -= momentum / totalMass;
    for (int i = 0; i < numParticles; i++)
        kinetic += 0.5 * masses[i] * velocities[i].dot(velocities[i]);
    const int dof = topology.getNumDegreesOfFreedom(getBodyDegreesOfFreedom());
    if (kinetic > 0 && dof > 0)
        for (Vec3& v : velocities)
            v *= std::sqrt(0.5 * dof * BOLTZ * temperature / kinetic);
    return velocities;
}

double CommonIntegrateMRattleStepKernel::computeKineticEnergy(ContextImpl& context) {
    ContextSelector selector(cc);
    checkFailure();
    return cc.getIntegrationUtilities().computeKineticEnergy(0.0);
}

void CommonIntegrateMRattleStepKernel::computeKineticEnergies(ContextImpl& context, double& translational,
                                                              double& rotational, double& free) {
    ContextSelector selector(cc);
    checkFailure();
    bodyKineticEnergy->compute(translational, rotational, free);
}

bool CommonIntegrateMRattleStepKernel::isBodyLinear(int index) const {
    return shapes[index] == RigidBodyMath::Shape::Linear;
}

int CommonIntegrateMRattleStepKernel::getBodyDegreesOfFreedom() const {
    int dof = 0;
    for (RigidBodyMath::Shape shape : shapes)
        dof += RigidBodyMath::degreesOfFreedom(shape);
    return dof;
}

void CommonIntegrateMRattleStepKernel::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    // The random stream (Andersen collisions) is OpenMM's IntegrationUtilities', which
    // OpenMM's own part of the checkpoint holds: the kernel adds an empty state.
    int32_t length = 0;
    stream.write(reinterpret_cast<const char*>(&length), sizeof(length));
}

void CommonIntegrateMRattleStepKernel::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    int32_t length = -1;
    stream.read(reinterpret_cast<char*>(&length), sizeof(length));
    if (!stream || stream.gcount() != (std::streamsize) sizeof(length))
        throw OpenMMException("the checkpoint is truncated (it ends before the kernel's state)");
    if (length != 0)
        throw OpenMMException("the checkpoint's kernel data is not this platform's (a state of " + std::to_string(length) +
                              " bytes where none is expected)");
    ContextSelector selector(cc);
    failure.upload(vector<int>(1, 0));
    stepsSinceFailureCheck = 0;
}
