/*
 * CommonRigidBodyState: set-up, atom order, kinetic energies, velocities set from the host,
 * and the integrator's declared arrays.
 */
#include "CommonRigidBodyState.h"
#include "CommonMRattleKernelSources.h"
#include "internal/FiniteValues.h"
#include "internal/ThermalVelocities.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/common/ComputeForceInfo.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/common/IntegrationUtilities.h"
#include "openmm/internal/ContextImpl.h"
#include <algorithm>
#include <functional>

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

/**
 * The bodies as particle groups joined like a bond's atoms, so that OpenMM's reordering (which
 * wraps each molecule into the box on its own) keeps a body of several molecules whole.
 */
class BodyForceInfo : public ComputeForceInfo {
public:
    explicit BodyForceInfo(const vector<vector<int> >& bodies) : bodies(bodies) {
    }
    int getNumParticleGroups() override {
        return bodies.size();
    }
    void getParticlesInGroup(int index, vector<int>& particles) override {
        particles = bodies[index];
    }
    /** Bodies of one size may be swapped: the state maps atoms anew after a reorder. */
    bool areGroupsIdentical(int group1, int group2) override {
        return bodies[group1].size() == bodies[group2].size();
    }

private:
    vector<vector<int> > bodies;
};

} // namespace

class CommonRigidBodyState::ReorderListener : public ComputeContext::ReorderListener {
public:
    explicit ReorderListener(CommonRigidBodyState& owner) : owner(owner) {
    }
    void execute() override {
        owner.mapAtoms();
        owner.reordered = true;
        owner.atomsReordered();
    }

private:
    CommonRigidBodyState& owner;
};

CommonRigidBodyState::CommonRigidBodyState(ComputeContext& cc, const std::string& integratorName)
    : cc(cc), integratorName(integratorName) {
}

void CommonRigidBodyState::initialize(const System& system, const RigidBodyTopology& topology,
                                      const std::string& sources) {
    ContextSelector selector(cc);
    // Whole bodies across reorderings: OpenMM builds its molecules once, when it initializes.
    cc.addForce(new BodyForceInfo(topology.getBodies()));
    cc.initializeContexts();
    bodies = topology;
    numBodies = bodies.getNumBodies();
    shapeConstraints.reset(new BodyShapeConstraints(system, bodies));
    shapes.assign(numBodies, RigidBodyMath::Shape::General);
    inverseMasses.resize(system.getNumParticles());
    for (int i = 0; i < system.getNumParticles(); i++)
        inverseMasses[i] = (system.getParticleMass(i) == 0 ? 0.0 : 1.0 / system.getParticleMass(i));
    vector<int> starts = {0}, large;
    for (int b = 0; b < numBodies; b++) {
        for (int atom : bodies.getBodyParticles(b))
            systemBodyAtoms.push_back(atom);
        starts.push_back(systemBodyAtoms.size());
        if (bodies.getBodyParticles(b).size() > LargeBodyAtoms)
            large.push_back(b);
    }
    numLargeBodies = large.size();
    large.resize(std::max<size_t>(1, large.size()), 0);
    largeBodies.initialize<int>(cc, large.size(), "mrattleLargeBodies");
    largeBodies.upload(large);
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
    bodyStart.initialize<int>(cc, starts.size(), "mrattleBodyStart");
    bodyStart.upload(starts);
    bodyAtoms.initialize<int>(cc, std::max<size_t>(1, systemBodyAtoms.size()), "mrattleBodyAtoms");
    bodyShape.initialize<int>(cc, std::max(1, numBodies), "mrattleBodyShape");
    uploadedShapeCodes.assign(std::max(1, numBodies), shapeCode(RigidBodyMath::Shape::General));
    bodyShape.upload(uploadedShapeCodes);
    clusterStart.initialize<int>(cc, clusterStarts.size(), "mrattleClusterStart");
    clusterStart.upload(clusterStarts);
    constraintAtoms.initialize<mm_int2>(cc, std::max<size_t>(1, distances.size()), "mrattleConstraintAtoms");
    distances.resize(std::max<size_t>(1, distances.size()), 0.0);
    initializeMixedArray(constraintDistance, distances, "mrattleConstraintDistance");
    clusterAtomStart.initialize<int>(cc, clusterAtomStarts.size(), "mrattleClusterAtomStart");
    clusterAtomStart.upload(clusterAtomStarts);
    clusterAtoms.initialize<int>(cc, std::max<size_t>(1, systemClusterAtoms.size()), "mrattleClusterAtoms");
    freeAtoms.initialize<int>(cc, std::max<size_t>(1, systemFreeAtoms.size()), "mrattleFreeAtoms");
    bodyReference.initialize(cc, std::max<size_t>(1, systemBodyAtoms.size()),
                             doubleMixed() ? sizeof(mm_double4) : sizeof(mm_float4), "mrattleBodyReference");
    bodyReference.upload(vector<mm_double4>(bodyReference.getSize(), mm_double4(0, 0, 0, 0)), true);
    initializeMixedArray(bodyOrientation, identityOrientations(), "mrattleBodyOrientation");
    bodyFrame.initialize<mm_int4>(cc, std::max(1, numBodies), "mrattleBodyFrame");
    screenVerdict.initialize<int>(cc, 1, "mrattleScreenVerdict");
    screenVerdict.upload(vector<int>(1, 0));
    // The factors of the next scaling: every velocity's (and the Drude groups' R), and the Drude groups' C.
    initializeMixedArray(velocityScale, {1.0, 1.0}, "mrattleVelocityScale");
    // A launch has at most getNumThreadBlocks() work groups (OpenMM's rule, both platforms).
    initializeMixedArray(partials, vector<double>(cc.getNumThreadBlocks(), 0.0), "mrattlePartialSums");
    partialCount.initialize<int>(cc, 1, "mrattlePartialCount");
    partialCount.upload(vector<int>(1, 0));
    // The integrator's declared arrays (none yet: one unread number).
    initializeMixedArray(integratorArrays, {0.0}, "mrattleIntegratorArrays");
    initializeMixedArray(integratorBackup, {0.0}, "mrattleIntegratorBackup");
    initializeFailure();
    mapAtoms();
    cc.addReorderListener(new ReorderListener(*this));
    for (int f = 0; f < system.getNumForces(); f++)
        if (const AndersenThermostat* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f))) {
            hasAndersen = true;
            initRandomNumbers(thermostat->getRandomNumberSeed());
        }
    stepProgram = cc.compileProgram(programSource((hasAndersen ? CommonMRattleKernelSources::collisions : "") + sources),
                                    programDefines(cc.getUseDoublePrecision(), cc.getUseMixedPrecision()));
    advanceGroups = stepProgram->createKernel("advanceGroups");
    projectBodies = stepProgram->createKernel("projectBodies");
    advanceLargeBodies = stepProgram->createKernel("advanceLargeBodies");
    projectLargeBodies = stepProgram->createKernel("projectLargeBodies");
    constrainFreeVelocities = stepProgram->createKernel("constrainFreeVelocities");
    partialSums = stepProgram->createKernel("kineticEnergyPartialSums");
    findUnusable = stepProgram->createKernel("findUnusableVelocities");
    findUnusable->addArg(cc.getNumAtoms());
    findUnusable->addArg(cc.getVelm());
    findUnusable->addArg(screenVerdict);
    if (hasAndersen) {
        collideBodies = stepProgram->createKernel("collideBodies");
        collideLargeBodies = stepProgram->createKernel("collideLargeBodies");
    }
}

void CommonRigidBodyState::initRandomNumbers(int seed) {
    // Now, not at the first step: OpenMM's checkpoints hold the device random state only once
    // the generator exists, so a new Context must have it before loading one.
    if (hasRandomNumbers)
        return;
    cc.getIntegrationUtilities().initRandomNumberGenerator(seed);
    hasRandomNumbers = true;
}

void CommonRigidBodyState::mapAtoms() {
    // cc.getAtomIndex()[i] is the System index of the atom the device holds at i.
    const vector<int>& order = cc.getAtomIndex();
    // A damaged checkpoint can hand OpenMM an order that is no permutation: map nothing then
    // (the integrator refuses to step until the Context is set up again).
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
    upload(systemDrudeGroupAtoms, drudeGroupAtoms);
    upload(systemDrudeGroupPlaces, drudeGroupPlaces);
    upload(systemUngroupedAtoms, ungroupedAtoms);
    upload(systemDrudePairAtoms, drudePairAtoms);
    if (!systemConstraintAtoms.empty()) {
        vector<mm_int2> atoms(systemConstraintAtoms.size() / 2);
        for (size_t k = 0; k < atoms.size(); k++)
            atoms[k] = mm_int2(deviceIndex[systemConstraintAtoms[2 * k]], deviceIndex[systemConstraintAtoms[2 * k + 1]]);
        constraintAtoms.upload(atoms);
    }
}

void CommonRigidBodyState::projectVelocities(ContextImpl& context, double tolerance) {
    ContextSelector selector(cc);
    // On the device, with one 4-byte read: the given velocities kept in the step's backup
    // (free once every step is checked), projected, then screened. Anything unusable after
    // the projection puts the given ones back and leaves the verdict to the host's check.
    synchronize();
    cc.getVelm().copyTo(velmBackup);
    projectNow(tolerance, true);
    findUnusable->execute(cc.getNumAtoms());
    if (!screenFound())
        return;
    velmBackup.copyTo(cc.getVelm());
    projectVelocitiesOnHost(context, tolerance);
}

bool CommonRigidBodyState::screenFound() {
    int found;
    screenVerdict.download(&found);
    if (found != 0)
        screenVerdict.upload(vector<int>(1, 0));
    return found != 0;
}

void CommonRigidBodyState::projectVelocitiesOnHost(ContextImpl& context, double tolerance) {
    // The given velocities are on the device and in velmBackup.
    vector<Vec3> velocities;
    context.getVelocities(velocities);
    FiniteValues::require(velocities, "velocity");
    projectNow(tolerance, true);
    context.getVelocities(velocities);
    try {
        FiniteValues::require(velocities, "velocity projected at the current positions (a degenerate constraint?)");
    } catch (...) {
        velmBackup.copyTo(cc.getVelm());
        throw;
    }
}

vector<Vec3> CommonRigidBodyState::getVelocitiesForTemperature(ContextImpl& context, double temperature, int randomSeed,
                                                               double tolerance) {
    ContextSelector selector(cc);
    // Maxwell-Boltzmann per particle, projected on the device, then rescaled exactly to the temperature.
    vector<Vec3> velocities = ThermalVelocities::maxwellBoltzmann(inverseMasses, temperature, randomSeed);
    context.setVelocities(velocities);
    projectNow(tolerance, false);
    context.getVelocities(velocities);
    ThermalVelocities::scaleToTemperature(bodies, inverseMasses, degreesOfFreedom(), temperature, velocities);
    return velocities;
}

double CommonRigidBodyState::computeKineticEnergy(ContextImpl& context) {
    ContextSelector selector(cc);
    synchronize();
    return cc.getIntegrationUtilities().computeKineticEnergy(0.0);
}

void CommonRigidBodyState::computeKineticEnergies(ContextImpl& context, double& translational, double& rotational,
                                                  double& free) {
    ContextSelector selector(cc);
    synchronize();
    // The bodies' parts from the device (kernels/bodyKineticEnergy.cc); free = all - the bodies' atoms'.
    const double total = cc.getIntegrationUtilities().computeKineticEnergy(0.0);
    translational = rotational = 0;
    double inBodies = 0;
    if (numBodies > 0) {
        if (!bodyKineticEnergy) {
            initializeMixedArray(bodyEnergies, vector<double>(3 * numBodies, 0.0), "mrattleBodyEnergies");
            bodyKineticEnergy = stepProgram->createKernel("bodyKineticEnergy");
            Arguments arguments(bodyKineticEnergy, doubleMixed());
            arguments.add(numBodies);
            arguments.add(bodyStart);
            arguments.add(bodyAtoms);
            arguments.add(cc.getVelm());
            arguments.add(bodyEnergies);
            largeBodyKineticEnergy = stepProgram->createKernel("largeBodyKineticEnergy");
            Arguments large(largeBodyKineticEnergy, doubleMixed());
            large.add(largeBodies);
            large.add(numLargeBodies);
            large.add(bodyStart);
            large.add(bodyAtoms);
            large.add(cc.getVelm());
            large.add(bodyEnergies);
        }
        bodyKineticEnergy->execute(numBodies);
        if (numLargeBodies > 0)
            largeBodyKineticEnergy->execute(numLargeBodies * LargeBodyThreads, LargeBodyThreads);
        const vector<double> values = downloadAsDouble(bodyEnergies);
        for (int b = 0; b < numBodies; b++) {
            translational += values[3 * b];
            rotational += values[3 * b + 1];
            inBodies += values[3 * b + 2];
        }
    }
    free = total - inBodies;
}

void CommonRigidBodyState::finishSteps(ContextImpl& context) {
    ContextSelector selector(cc);
    synchronize();
}

bool CommonRigidBodyState::isBodyLinear(int index) const {
    return shapes[index] == RigidBodyMath::Shape::Linear;
}

int CommonRigidBodyState::getBodyDegreesOfFreedom() const {
    return RigidBodyTopology::getBodyDegreesOfFreedom(shapes);
}

int CommonRigidBodyState::degreesOfFreedom() const {
    return bodies.getNumDegreesOfFreedom(getBodyDegreesOfFreedom());
}

vector<int> CommonRigidBodyState::declareIntegratorArrays(const vector<std::pair<std::string, int> >& arrays,
                                                         bool lengthFirst) {
    ContextSelector selector(cc);
    // One array for all, so that the step's backup of them is one copy in its first launch.
    vector<int> offsets;
    for (const auto& array : arrays) {
        declared.push_back({array.first, integratorSize, array.second});
        offsets.push_back(integratorSize);
        integratorSize += array.second;
    }
    this->lengthFirst = lengthFirst;
    const vector<double> zeros(std::max(1, integratorSize), 0.0);
    integratorArrays.resize(zeros.size());
    integratorBackup.resize(zeros.size());
    integratorArrays.upload(zeros, true);
    integratorBackup.upload(zeros, true);
    return offsets;
}

IntegratorParameterValues CommonRigidBodyState::getIntegratorParameters(ContextImpl& context) {
    ContextSelector selector(cc);
    return integratorValues();
}

IntegratorParameterValues CommonRigidBodyState::integratorValues() const {
    IntegratorParameterValues values;
    if (declared.empty())
        return values;
    const vector<double> all = downloadAsDouble(integratorArrays);
    for (const DeclaredArray& array : declared)
        values[array.name].assign(all.begin() + array.offset, all.begin() + array.offset + array.size);
    return values;
}

void CommonRigidBodyState::setIntegratorParameters(ContextImpl& context, const IntegratorParameterValues& values) {
    ContextSelector selector(cc);
    if (declared.empty())
        return;
    vector<double> all = downloadAsDouble(integratorArrays);
    for (const DeclaredArray& array : declared)
        std::copy(values.at(array.name).begin(), values.at(array.name).end(), all.begin() + array.offset);
    integratorArrays.upload(all, true);  // values read from this precision: exact
}

void CommonRigidBodyState::initializeMixedArray(ComputeArray& array, const vector<double>& values, const std::string& name) {
    array.initialize(cc, values.size(), doubleMixed() ? sizeof(double) : sizeof(float), name);
    array.upload(values, true);  // converted to float in single precision
}

vector<double> CommonRigidBodyState::downloadAsDouble(const ArrayInterface& array, int perElement) {
    const size_t count = array.getSize() * perElement;
    vector<double> values(count);
    if (array.getElementSize() == perElement * (int) sizeof(double))
        array.download(values.data());
    else {
        vector<float> single(count);
        array.download(single.data());
        values.assign(single.begin(), single.end());
    }
    return values;
}

void CommonRigidBodyState::uploadFromDouble(ArrayInterface& array, const vector<double>& values, int perElement) {
    if (array.getElementSize() == perElement * (int) sizeof(double))
        array.upload(values.data());
    else {
        vector<float> single(values.begin(), values.end());
        array.upload(single.data());
    }
}
