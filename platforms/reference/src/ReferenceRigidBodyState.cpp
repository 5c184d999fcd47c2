#include "ReferenceRigidBodyState.h"
#include "RigidBodyIntegrator.h"
#include "internal/FiniteValues.h"
#include "internal/RigidBodyKernels.h"
#include "internal/ThermalVelocities.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/kernels.h"
#include "openmm/reference/ReferencePlatform.h"
#include <cmath>
#include <cstdint>
#include <istream>
#include <ostream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

ReferencePlatform::PlatformData& platformData(ContextImpl& context) {
    // The CPU platform derives from the Reference platform and keeps this data too.
    return *reinterpret_cast<ReferencePlatform::PlatformData*>(context.getPlatformData());
}

vector<Vec3>& positionsOf(ContextImpl& context) {
    return *platformData(context).positions;
}

vector<Vec3>& velocitiesOf(ContextImpl& context) {
    return *platformData(context).velocities;
}

uint64_t seedOf(int seed) {
    return seed != 0 ? (uint64_t) seed : (uint64_t) std::random_device()();
}

/**
 * A checkpoint of format 3 framed the state's data again, with its length (int32,
 * native-endian) before the random stream's text: skip that frame if the stream has one. The
 * text starts with a digit, so its first four bytes read as a length are at least
 * 0x30303030: never the length of the rest, which is how a frame is told apart.
 */
void skipFormat3Frame(std::istream& stream) {
    const std::streampos start = stream.tellg();
    stream.seekg(0, std::ios::end);
    const std::streamoff rest = stream.tellg() - start;
    stream.seekg(start);
    int32_t length = -1;
    if (rest >= (std::streamoff) sizeof(length))
        stream.read(reinterpret_cast<char*>(&length), sizeof(length));
    if (!(length >= 0 && length == rest - (std::streamoff) sizeof(length)))
        stream.seekg(start);
}

} // namespace

ReferenceRigidBodyState::ReferenceRigidBodyState(const std::string& stepKernelName)
    : integratorName(IntegratorNames::ofStepKernel(stepKernelName).integrator) {
}

void ReferenceRigidBodyState::initialize(const System& system, const RigidBodyTopology& topology) {
    bodies = topology;
    const int n = system.getNumParticles();
    inverseMass.resize(n);
    this->mass.resize(n);
    for (int i = 0; i < n; i++) {
        const double mass = system.getParticleMass(i);
        inverseMass[i] = (mass == 0.0 ? 0.0 : 1.0 / mass);
        this->mass[i] = mass;
        hasVirtualSites |= system.isVirtualSite(i);
    }
    shapes.assign(bodies.getNumBodies(), RigidBodyMath::Shape::General);
    for (int b = 0; b < bodies.getNumBodies(); b++) {
        const vector<int>& atoms = bodies.getBodyParticles(b);
        views.push_back(RigidBodyMath::BodyView{atoms.data(), (int) atoms.size(), bodies.getMasses().data(),
                                                bodies.getBodyMass(b), false});
    }
    shapeConstraints.reset(new BodyShapeConstraints(system, bodies));
    vector<bool> free(n, false);
    for (int i : bodies.getFreeParticles())
        free[i] = true;
    for (int i = 0; i < n; i++)
        if (bodies.getBodyOfParticle(i) < 0 && !free[i])
            otherParticles.push_back(i);
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
            freeConstraintAtoms.push_back({p1, p2});
            freeConstraintDistances.push_back(distance);
        }
        freeConstraints.reset(new ReferenceConstraints(freeSystem));
    }
    for (int f = 0; f < system.getNumForces(); f++)
        if (const auto* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f))) {
            andersen = true;
            random.seed(seedOf(thermostat->getRandomNumberSeed()));
            randomIsSet = true;
        }
    nextPositions.resize(n);
    nextVelocities.resize(n);
}

void ReferenceRigidBodyState::declareIntegratorState(const Variables& declared, bool lengthFirst,
                                                     bool withRandomStream) {
    variables = declared;
    lengthInCheckpoint = lengthFirst;
    randomInStep = withRandomStream;
    startVariables.resize(variables.size());
}

void ReferenceRigidBodyState::seedRandom(int seed) {
    if (randomIsSet)
        return;
    random.seed(seedOf(seed));
    randomIsSet = true;
}

int ReferenceRigidBodyState::getNumDegreesOfFreedom() const {
    return bodies.getNumDegreesOfFreedom(getBodyDegreesOfFreedom());
}

// ---- The phases of a step ------------------------------------------------------------------

void ReferenceRigidBodyState::beginStep(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                        bool& forcesAreValid) {
    stepContext = &context;
    forcesComputed = false;
    if (!threadsChecked) {
        // The platform's properties cannot be asked for while the Context is being made.
        threadsChecked = true;
        if (context.getPlatform().getName() == "CPU")
            setThreads(std::stoi(context.getPlatform().getPropertyValue(context.getOwner(), "Threads")));
    }
    if (andersen)
        collideBodies(positions(), velocities(), context.getParameter(AndersenThermostat::Temperature()),
                      integrator.getConstraintTolerance());
    if (!forcesAreValid)
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    startPositions = positions();
    startVelocities = velocities();
    for (size_t i = 0; i < variables.size(); i++)
        startVariables[i] = *variables[i].second;
    if (randomInStep)
        startRandom = random;
}

void ReferenceRigidBodyState::project(double tolerance) {
    phase([&] { projectArrays(positions(), velocities(), tolerance); });
}

void ReferenceRigidBodyState::computeForces(ContextImpl& context, const RigidBodyIntegrator& integrator,
                                            bool& forcesAreValid) {
    forcesAreValid = false;
    forcesComputed = true;
    phase([&] {
        // OpenMM's Reference code loops over every particle to find virtual sites: skipped without any.
        if (hasVirtualSites)
            context.computeVirtualSites();
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    });
}

void ReferenceRigidBodyState::endStep(double stepSize, bool& forcesAreValid) {
    phase([&] { requireFiniteStepResult(); });
    // A step without a computeForces phase leaves the forces to the next step's start.
    if (!forcesComputed && hasVirtualSites)
        stepContext->computeVirtualSites();
    ReferencePlatform::PlatformData& data = platformData(*stepContext);
    data.time += stepSize;
    data.stepCount++;
    forcesAreValid = forcesComputed;
    forcesComputed = false;
    stepContext = nullptr;
}

// ---- Failure and rollback ----------------------------------------------------------------

void ReferenceRigidBodyState::phase(const std::function<void()>& work) {
    try {
        work();
    } catch (const OpenMMException& e) {
        failStep(e.what());
    }
}

void ReferenceRigidBodyState::failStep(const std::string& what) {
    positions() = startPositions;
    velocities() = startVelocities;
    for (size_t i = 0; i < variables.size(); i++)
        *variables[i].second = startVariables[i];
    if (randomInStep)
        random = startRandom;
    stepContext = nullptr;
    throw OpenMMException(integratorName + ": " + what +
                          "; the step was not taken (positions and velocities are as before it)");
}

void ReferenceRigidBodyState::requireFiniteStepResult() {
    const vector<Vec3>& x = positions();
    const vector<Vec3>& v = velocities();
    const vector<Vec3>& f = forces();
    for (size_t i = 0; i < x.size(); i++) {
        if (inverseMass[i] == 0)
            continue;  // massless: never integrated, finite since set
        const char* what = !std::isfinite(x[i][0] + x[i][1] + x[i][2])   ? "position"
                           : !std::isfinite(f[i][0] + f[i][1] + f[i][2]) ? "force at the new positions"
                           : !std::isfinite(v[i][0] + v[i][1] + v[i][2]) ? "velocity"
                                                                         : nullptr;
        if (what != nullptr)
            throw OpenMMException(std::string("the ") + what + " of particle " + std::to_string(i) + " is not finite");
    }
}

vector<Vec3>& ReferenceRigidBodyState::positions() {
    return positionsOf(*stepContext);
}

vector<Vec3>& ReferenceRigidBodyState::velocities() {
    return velocitiesOf(*stepContext);
}

const vector<Vec3>& ReferenceRigidBodyState::forces() {
    return *platformData(*stepContext).forces;
}

void ReferenceRigidBodyState::acceptNewState() {
    positions().swap(nextPositions);
    velocities().swap(nextVelocities);
}

// ---- What the API asks ---------------------------------------------------------------------

void ReferenceRigidBodyState::updateShapes(ContextImpl& context) {
    vector<Vec3>& x = positionsOf(context);
    FiniteValues::require(x, "position");
    if (shapeConstraints->apply(x, 0, &shapes))  // the shapes at the positions it leaves
        context.computeVirtualSites();
    // A point rotates no more than a line does: both take the linear body's arithmetic.
    for (int b = 0; b < bodies.getNumBodies(); b++)
        views[b].linear = (shapes[b] != RigidBodyMath::Shape::General);
}

void ReferenceRigidBodyState::projectVelocities(ContextImpl& context, double tolerance) {
    vector<Vec3>& v = velocitiesOf(context);
    FiniteValues::require(v, "velocity");
    const vector<Vec3> given = v;  // only when velocities are set, not in the step
    try {
        projectNonRigidArrays(positionsOf(context), v, tolerance);
        FiniteValues::require(v, "velocity projected at the current positions (a degenerate constraint?)");
    } catch (...) {
        v = given;  // a refused projection (not finite, or constraints not converged) changes nothing
        throw;
    }
}

vector<Vec3> ReferenceRigidBodyState::getVelocitiesForTemperature(ContextImpl& context, double temperature,
                                                                  int randomSeed, double tolerance) {
    // Maxwell-Boltzmann per particle, projected (which keeps the distribution's form on the
    // rigid degrees of freedom), then rescaled to exactly the temperature.
    vector<Vec3> v = ThermalVelocities::maxwellBoltzmann(inverseMass, temperature, randomSeed);
    projectArrays(positionsOf(context), v, tolerance);
    ThermalVelocities::scaleToTemperature(bodies, inverseMass, getNumDegreesOfFreedom(), temperature, v);
    return v;
}

double ReferenceRigidBodyState::computeKineticEnergy(ContextImpl& context) {
    return kineticEnergyOf(velocitiesOf(context));
}

void ReferenceRigidBodyState::computeKineticEnergies(ContextImpl& context, double& translational, double& rotational,
                                                     double& free) {
    const vector<Vec3>& v = velocitiesOf(context);
    translational = rotational = free = 0;
    for (int b = 0; b < bodies.getNumBodies(); b++) {
        const vector<int>& atoms = bodies.getBodyParticles(b);
        Vec3 momentum;
        for (int i : atoms)   // body members are massive
            momentum += v[i] / inverseMass[i];
        const double mass = bodies.getBodyMass(b);
        const Vec3 center = momentum / mass;
        translational += 0.5 * mass * center.dot(center);
        for (int i : atoms) {
            const Vec3 relative = v[i] - center;
            rotational += 0.5 * relative.dot(relative) / inverseMass[i];
        }
    }
    for (int i : bodies.getFreeParticles())
        free += 0.5 * v[i].dot(v[i]) / inverseMass[i];
}

int ReferenceRigidBodyState::getBodyDegreesOfFreedom() const {
    return RigidBodyTopology::getBodyDegreesOfFreedom(shapes);
}

void ReferenceRigidBodyState::createCheckpoint(ContextImpl& context, std::ostream& stream) const {
    // Unframed (the checkpoint header frames it): the declared variables, then the random
    // stream as text, which reads to the end.
    vector<const vector<double>*> values;
    for (const auto& variable : variables)
        values.push_back(variable.second);
    if (!values.empty())
        writeIntegratorVariables(stream, values, lengthInCheckpoint);
    stream << random;
}

void ReferenceRigidBodyState::loadCheckpoint(ContextImpl& context, std::istream& stream) {
    // Read aside first: nothing changes unless all of it fits.
    vector<vector<double> > read;
    vector<vector<double>*> into;
    std::string names;
    for (const auto& variable : variables) {
        read.push_back(*variable.second);
        names += (names.empty() ? "" : " and ") + variable.first;
    }
    for (vector<double>& values : read)
        into.push_back(&values);
    if (!into.empty())
        readIntegratorVariables(stream, names, into, lengthInCheckpoint);
    skipFormat3Frame(stream);
    std::mt19937_64 generator;
    stream >> generator;
    if (stream.fail())
        throw OpenMMException("the checkpoint's kernel data is malformed (its random state cannot be read)");
    random = generator;
    randomIsSet = true;
    for (size_t i = 0; i < variables.size(); i++)
        *variables[i].second = read[i];
}

void ReferenceRigidBodyState::discardRefusedCheckpoint(ContextImpl& context) {
    // OpenMM's Reference and CPU platforms keep one process-wide random generator (the
    // AndersenThermostat's, among others) whose state a checkpoint overwrites unchecked.
    // Initialising OpenMM's thermostat kernel reseeds it (with the System's thermostat seed
    // if it has one), so it rebuilds a valid state.
    AndersenThermostat seeded(0, 0);
    const System& system = context.getSystem();
    for (int f = 0; f < system.getNumForces(); f++)
        if (const auto* thermostat = dynamic_cast<const AndersenThermostat*>(&system.getForce(f)))
            seeded.setRandomNumberSeed(thermostat->getRandomNumberSeed());
    Kernel reseed = context.getPlatform().createKernel(ApplyAndersenThermostatKernel::Name(), context);
    reseed.getAs<ApplyAndersenThermostatKernel>().initialize(system, seeded);
}

IntegratorParameterValues ReferenceRigidBodyState::getIntegratorParameters(ContextImpl& context) {
    IntegratorParameterValues values;
    for (const auto& variable : variables)
        values[variable.first] = *variable.second;
    return values;
}

void ReferenceRigidBodyState::setIntegratorParameters(ContextImpl& context, const IntegratorParameterValues& values) {
    for (const auto& variable : variables)
        *variable.second = values.at(variable.first);
}
