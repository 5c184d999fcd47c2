#include "RigidBodyIntegrator.h"
#include "internal/OpenMMVersionCheck.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <random>
#include <sstream>
#include <streambuf>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

// The integrator's part of a checkpoint (OpenMM writes it after the Context's own data):
// magic, format version, the step kernel's name, the number of bodies in effect and a
// signature of their memberships, then the subclass's writeCheckpointState(). Numbers are
// native-endian, like the rest of an OpenMM checkpoint.
const char CheckpointMagic[8] = {'M', 'R', 'a', 't', 't', 'l', 'e', 'C'};
const int32_t CheckpointVersion = 1;
const int32_t MaxKernelNameLength = 1024;

template <class T>
void writeValue(std::ostream& stream, T value) {
    stream.write(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <class T>
T readValue(std::istream& stream, const char* what) {
    T value;
    stream.read(reinterpret_cast<char*>(&value), sizeof(T));
    if (!stream || stream.gcount() != (std::streamsize) sizeof(T))
        throw OpenMMException(std::string("the checkpoint is truncated (it ends before the ") + what + ")");
    return value;
}

/**
 * FNV-1a hash of the partition of particles into bodies: for each particle, the smallest
 * index in its body, or -1. Equal for the same bodies whatever order they, or their
 * members, were listed in.
 */
uint64_t bodySignature(const RigidBodySet& bodies, int numParticles) {
    vector<int32_t> representative(numParticles, -1);
    for (const vector<int>& body : bodies.getBodies()) {
        int smallest = *std::min_element(body.begin(), body.end());
        for (int particle : body)
            representative[particle] = smallest;
    }
    uint64_t hash = 14695981039346656037ULL;
    const unsigned char* bytes = reinterpret_cast<const unsigned char*>(representative.data());
    for (size_t i = 0; i < representative.size() * sizeof(int32_t); i++) {
        hash ^= bytes[i];
        hash *= 1099511628211ULL;
    }
    return hash;
}

std::string hex(uint64_t value) {
    std::ostringstream text;
    text << "0x" << std::hex << value;
    return text.str();
}

/** Appends what is written to a vector, which keeps its capacity from one checkpoint to the next. */
class VectorWriteBuffer : public std::streambuf {
public:
    explicit VectorWriteBuffer(vector<char>& out) : out(out) {
    }

protected:
    std::streamsize xsputn(const char* data, std::streamsize count) override {
        out.insert(out.end(), data, data + count);
        return count;
    }
    int_type overflow(int_type c) override {
        if (!traits_type::eq_int_type(c, traits_type::eof()))
            out.push_back(traits_type::to_char_type(c));
        return traits_type::not_eof(c);
    }

private:
    vector<char>& out;
};

/** Reads a block of memory in place. */
class MemoryReadBuffer : public std::streambuf {
public:
    MemoryReadBuffer(const vector<char>& data) {
        char* begin = const_cast<char*>(data.data());
        setg(begin, begin, begin + data.size());
    }
};

} // namespace

RigidBodyIntegrator::RigidBodyIntegrator() {
    setConstraintTolerance(1e-5);
}

int RigidBodyIntegrator::addRigidBody(const vector<int>& particles) {
    if (owner != nullptr)
        throw OpenMMException("addRigidBody: bodies cannot be added once the integrator is bound to a Context");
    RigidBodySet::checkBodyDefinition(declaredBodies.size(), particles);
    declaredBodies.push_back(particles);
    return declaredBodies.size() - 1;
}

int RigidBodyIntegrator::getNumRigidBodies() const {
    return declaredBodies.size();
}

const vector<int>& RigidBodyIntegrator::getRigidBodyParticles(int index) const {
    if (index < 0 || index >= (int) declaredBodies.size())
        throw OpenMMException("getRigidBodyParticles: body index " + std::to_string(index) + " is out of range (" +
                              std::to_string(declaredBodies.size()) + " bodies declared)");
    return declaredBodies[index];
}

void RigidBodyIntegrator::requireContext() const {
    if (context == nullptr)
        throw OpenMMException("This Integrator is not bound to a context!");
}

const RigidBodySet& RigidBodyIntegrator::getRigidBodySet() const {
    requireContext();
    return bodySet;
}

const vector<vector<int> >& RigidBodyIntegrator::getBodiesInEffect() const {
    return getRigidBodySet().getBodies();
}

int RigidBodyIntegrator::getNumBodiesInEffect() const {
    return getRigidBodySet().getNumBodies();
}

bool RigidBodyIntegrator::isBodyLinear(int index) const {
    const RigidBodySet& set = getRigidBodySet();
    if (index < 0 || index >= set.getNumBodies())
        throw OpenMMException("isBodyLinear: body index " + std::to_string(index) + " is out of range (" +
                              std::to_string(set.getNumBodies()) + " bodies in effect)");
    return set.isLinear(index);
}

const vector<int>& RigidBodyIntegrator::getFreeParticles() const {
    return getRigidBodySet().getFreeParticles();
}

int RigidBodyIntegrator::getNumDegreesOfFreedom() const {
    return getRigidBodySet().getNumDegreesOfFreedom();
}

void RigidBodyIntegrator::initialize(ContextImpl& contextRef) {
    if (owner != nullptr && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    checkOpenMMVersion(Platform::getOpenMMVersion());
    const System& system = contextRef.getSystem();
    bodySet = RigidBodySet(system, declaredBodies, contextRef.getMolecules());
    hasVelocityChangingForce = false;
    for (int i = 0; i < system.getNumForces(); i++)
        if (dynamic_cast<const AndersenThermostat*>(&system.getForce(i)) != nullptr)
            hasVelocityChangingForce = true;
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = contextRef.getPlatform().createKernel(getStepKernelName(), contextRef);
    kernel.getAs<RigidBodyKernel>().initialize(system, bodySet);
    forcesAreValid = false;
    restoringCheckpoint = false;
    rollingBack = false;
    refreshCachesBeforeStep = false;
    rollbackParameterNames.clear();
    for (const auto& parameter : contextRef.getParameters())
        rollbackParameterNames.push_back(parameter.first);
    saveRollbackState();
}

void RigidBodyIntegrator::cleanup() {
    kernel = Kernel();
    rollbackState = vector<char>();
    rollbackStateIsCurrent = false;
}

vector<std::string> RigidBodyIntegrator::getKernelNames() {
    return {getStepKernelName()};
}

void RigidBodyIntegrator::stateChanged(State::DataType changed) {
    // Changes the integrator makes itself (inProjection) are handled where it makes them.
    if (inProjection)
        return;
    forcesAreValid = false;
    if (context == nullptr)
        return;
    if (changed == State::Positions) {
        vector<Vec3> positions;
        context->getPositions(positions);
        bodySet.updateShapes(positions);
    }
    if (changed == State::Energy)
        restoringCheckpoint = false;  // the last notification of a checkpoint load
    // Velocities the user sets are made rigid at once, so what the Context reports is
    // what the integrator uses. A checkpoint holds velocities that are already rigid:
    // projecting them again would change them at round-off and break exact restarts.
    if ((changed == State::Positions || changed == State::Velocities) && !restoringCheckpoint) {
        inProjection = true;
        kernel.getAs<RigidBodyKernel>().projectContextVelocities(*context, getConstraintTolerance());
        inProjection = false;
    }
    if (!restoringCheckpoint && !rollingBack)
        saveRollbackState();
}

void RigidBodyIntegrator::createCheckpoint(std::ostream& stream) const {
    requireContext();
    stream.write(CheckpointMagic, sizeof(CheckpointMagic));
    writeValue<int32_t>(stream, CheckpointVersion);
    const std::string kernelName = getStepKernelName();
    writeValue<int32_t>(stream, kernelName.size());
    stream.write(kernelName.data(), kernelName.size());
    writeValue<int32_t>(stream, bodySet.getNumBodies());
    writeValue<uint64_t>(stream, bodySignature(bodySet, context->getSystem().getNumParticles()));
    writeCheckpointState(stream);
    if (!takingRollbackState)
        refreshCachesBeforeStep = true;
}

void RigidBodyIntegrator::loadCheckpoint(std::istream& stream) {
    requireContext();
    // OpenMM calls this after it has read the Context's data and before it notifies
    // stateChanged(): the velocities it restored are already rigid, keep them bit for bit.
    restoringCheckpoint = true;
    std::string problem;
    try {
        char magic[sizeof(CheckpointMagic)];
        stream.read(magic, sizeof(magic));
        if (!stream || stream.gcount() != (std::streamsize) sizeof(magic))
            throw OpenMMException("the checkpoint holds no rigid-body integrator data: it is truncated, or it was "
                                  "written by a Context with a different integrator");
        if (!std::equal(magic, magic + sizeof(magic), CheckpointMagic))
            throw OpenMMException("the checkpoint's integrator data is not a rigid-body integrator's: it is malformed, "
                                  "or it was written by a Context with a different integrator");
        int32_t version = readValue<int32_t>(stream, "format version");
        if (version != CheckpointVersion)
            throw OpenMMException("the checkpoint's rigid-body integrator data has format version " +
                                  std::to_string(version) + ", and this build of the plugin reads version " +
                                  std::to_string(CheckpointVersion) + " only");
        int32_t nameLength = readValue<int32_t>(stream, "integrator name");
        if (nameLength < 0 || nameLength > MaxKernelNameLength)
            throw OpenMMException("the checkpoint's rigid-body integrator data is malformed (integrator name of length " +
                                  std::to_string(nameLength) + ")");
        std::string kernelName(nameLength, ' ');
        stream.read(&kernelName[0], nameLength);
        if (!stream || stream.gcount() != nameLength)
            throw OpenMMException("the checkpoint is truncated (it ends in the integrator name)");
        if (kernelName != getStepKernelName())
            throw OpenMMException("the checkpoint was written by an integrator using kernel '" + kernelName +
                                  "', and this one uses '" + getStepKernelName() +
                                  "': use saveState()/loadState() to change integrators");
        int32_t numBodies = readValue<int32_t>(stream, "number of rigid bodies");
        uint64_t signature = readValue<uint64_t>(stream, "rigid-body signature");
        uint64_t expected = bodySignature(bodySet, context->getSystem().getNumParticles());
        if (numBodies != bodySet.getNumBodies() || signature != expected)
            throw OpenMMException("the checkpoint was written with " + std::to_string(numBodies) +
                                  " rigid bodies in effect (signature " + hex(signature) + "), and this Context has " +
                                  std::to_string(bodySet.getNumBodies()) + " (signature " + hex(expected) +
                                  "): the bodies differ, so the System or the bodies declared with addRigidBody() are not "
                                  "those the checkpoint was written with");
        readCheckpointState(stream);
    } catch (const OpenMMException& e) {
        problem = e.what();
    }
    if (problem.empty()) {
        if (!rollingBack)
            refreshCachesBeforeStep = true;
        return;
    }
    restoringCheckpoint = false;
    if (rollingBack)
        throw OpenMMException("loadCheckpoint: " + problem);
    // OpenMM has already overwritten positions, velocities, time, box and parameters:
    // put back the Context's state from before this call.
    if (restoreRollbackState())
        throw OpenMMException("loadCheckpoint: " + problem + ". The Context was left as it was.");
    throw OpenMMException("loadCheckpoint: " + problem +
                          ". The Context's previous state could not be restored (a step had failed): set its "
                          "positions and velocities again.");
}

void RigidBodyIntegrator::saveRollbackState() {
    rollbackStateIsCurrent = false;
    rollbackState.clear();
    VectorWriteBuffer buffer(rollbackState);
    std::ostream stream(&buffer);
    takingRollbackState = true;
    try {
        context->createCheckpoint(stream);
    } catch (...) {
        takingRollbackState = false;
        throw;
    }
    takingRollbackState = false;
    rollbackStateIsCurrent = true;
}

void RigidBodyIntegrator::refreshForceCaches() {
    // A platform may keep data built from earlier positions: the CPU platform rebuilds its
    // neighbor list only once atoms have moved far enough, and the list's order changes
    // force sums at round-off. A run continued from a checkpoint starts with fresh caches,
    // so the run that wrote the checkpoint refreshes its caches at the same point (and so
    // does the one that loaded it): both then follow the same trajectory bit for bit.
    // Moving every atom by a box vector (or far, without a box) and back makes any such
    // cache be rebuilt at the current positions; the physics of the shifted copy does not
    // matter, its forces are discarded.
    vector<Vec3> positions;
    context->getPositions(positions);
    Vec3 a, b, c;
    context->getPeriodicBoxVectors(a, b, c);
    const Vec3 shift = (context->getSystem().usesPeriodicBoundaryConditions() ? a : Vec3(100.0, 0, 0));
    vector<Vec3> shifted(positions);
    for (Vec3& position : shifted)
        position += shift;
    forcesAreValid = false;  // the Context's forces will be the shifted copy's until computeForces()
    inProjection = true;     // these position changes are not the user's
    try {
        context->setPositions(shifted);
        context->calcForcesAndEnergy(true, false, getIntegrationForceGroups());
    } catch (...) {
        context->setPositions(positions);
        inProjection = false;
        throw;
    }
    context->setPositions(positions);
    inProjection = false;
    computeForces();
}

bool RigidBodyIntegrator::restoreRollbackState() {
    if (!rollbackStateIsCurrent)
        return false;
    MemoryReadBuffer buffer(rollbackState);
    std::istream stream(&buffer);
    rollingBack = true;
    try {
        context->loadCheckpoint(stream);
    } catch (const OpenMMException&) {
        rollingBack = false;
        return false;
    }
    rollingBack = false;
    // A checkpoint from another System may have added global parameters this Context does not have.
    auto& parameters = const_cast<std::map<std::string, double>&>(context->getParameters());
    for (auto iter = parameters.begin(); iter != parameters.end();) {
        if (std::find(rollbackParameterNames.begin(), rollbackParameterNames.end(), iter->first) ==
            rollbackParameterNames.end())
            iter = parameters.erase(iter);
        else
            ++iter;
    }
    return true;
}

double RigidBodyIntegrator::computeKineticEnergy() {
    return kernel.getAs<RigidBodyKernel>().computeKineticEnergy(*context);
}

vector<Vec3> RigidBodyIntegrator::getVelocitiesForTemperature(const System& system, double temperature,
                                                               int randomSeed) const {
    requireContext();
    if (!(temperature >= 0) || !std::isfinite(temperature))
        throw OpenMMException("setVelocitiesToTemperature: the temperature must be a finite number >= 0, got " +
                              std::to_string(temperature));
    // Maxwell-Boltzmann per particle, then the rigid-body projection (which keeps the
    // distribution's form on the rigid degrees of freedom), then an exact rescale to the
    // requested kinetic temperature with the rigid-body degrees of freedom.
    std::mt19937_64 generator(randomSeed);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    const int numParticles = system.getNumParticles();
    vector<Vec3> velocities(numParticles, Vec3());
    for (int i = 0; i < numParticles; i++) {
        double mass = system.getParticleMass(i);
        if (mass != 0 && !system.isVirtualSite(i)) {
            double scale = std::sqrt(BOLTZ * temperature / mass);
            double x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
            velocities[i] = Vec3(x, y, z) * scale;
        }
    }
    kernel.getAs<RigidBodyKernel>().projectVelocities(*context, velocities, getConstraintTolerance());
    double totalMass = 0;
    Vec3 momentum;
    for (int i = 0; i < numParticles; i++) {
        totalMass += system.getParticleMass(i);
        momentum += velocities[i] * system.getParticleMass(i);
    }
    if (bodySet.removesCenterOfMassMotion() && totalMass > 0) {
        Vec3 centerVelocity = momentum / totalMass;
        for (int i = 0; i < numParticles; i++)
            if (system.getParticleMass(i) != 0)
                velocities[i] -= centerVelocity;
    }
    double kinetic = 0;
    for (int i = 0; i < numParticles; i++)
        kinetic += 0.5 * system.getParticleMass(i) * velocities[i].dot(velocities[i]);
    int dof = bodySet.getNumDegreesOfFreedom();
    if (kinetic > 0 && dof > 0) {
        double scale = std::sqrt(0.5 * dof * BOLTZ * temperature / kinetic);
        for (Vec3& v : velocities)
            v *= scale;
    }
    return velocities;
}

void RigidBodyIntegrator::step(int steps) {
    requireContext();
    RigidBodyKernel& stepKernel = kernel.getAs<RigidBodyKernel>();
    for (int i = 0; i < steps; i++) {
        beginStep();
        ensureForces();
        stepKernel.integratePositions(*context, *this);
        computeForces();
        stepKernel.integrateVelocities(*context, *this);
    }
    endSteps();
}

void RigidBodyIntegrator::beginStep() {
    restoringCheckpoint = false;
    rollbackStateIsCurrent = false;
    if (getStepSize() == 0 || !std::isfinite(getStepSize()))
        throw OpenMMException("The step size must be a finite nonzero number of picoseconds, got " +
                              std::to_string(getStepSize()));
    if (context->updateContextState())
        forcesAreValid = false;
    if (hasVelocityChangingForce) {
        thermalizeCollidedBodies();
        kernel.getAs<RigidBodyKernel>().projectContextVelocities(*context, getConstraintTolerance());
    }
    if (refreshCachesBeforeStep) {
        refreshCachesBeforeStep = false;
        refreshForceCaches();
    }
}

void RigidBodyIntegrator::thermalizeCollidedBodies() {
    // AndersenThermostat randomizes single particles (or groups held by constraints).
    // Projecting a body of which only some atoms are fresh onto rigid motion does not keep
    // the rigid-body Boltzmann distribution (bonded water settles ~10% cold), while
    // projecting fresh Maxwell-Boltzmann velocities of all its atoms does. So a body with a
    // collided atom -- its velocities are no longer rigid -- collides as a whole. The
    // random numbers are seeded from the velocities the thermostat drew, so a run is
    // reproducible from a checkpoint.
    vector<Vec3> positions, velocities;
    context->getPositions(positions);
    context->getVelocities(velocities);
    vector<Vec3> rigid = velocities;
    double* rigidData = reinterpret_cast<double*>(rigid.data());
    const double* positionData = reinterpret_cast<const double*>(positions.data());
    const double temperature = context->getParameter(AndersenThermostat::Temperature());
    bool changed = false;
    for (int b = 0; b < bodySet.getNumBodies(); b++) {
        RigidBodyMath::projectBodyVelocities(bodySet.view(b), positionData, rigidData);
        double scale = 0, residual = 0;
        for (int i : bodySet.getBodyParticles(b)) {
            scale = std::max(scale, std::sqrt(velocities[i].dot(velocities[i])));
            Vec3 d = velocities[i] - rigid[i];
            residual = std::max(residual, std::sqrt(d.dot(d)));
        }
        if (!(residual > 1e-8 * scale))
            continue;  // still rigid: no collision
        uint64_t seed = 14695981039346656037ULL ^ (uint64_t) b;
        for (int i : bodySet.getBodyParticles(b)) {
            const unsigned char* bytes = reinterpret_cast<const unsigned char*>(&velocities[i]);
            for (size_t k = 0; k < sizeof(Vec3); k++)
                seed = (seed ^ bytes[k]) * 1099511628211ULL;
        }
        std::mt19937_64 generator(seed);
        std::normal_distribution<double> gaussian(0.0, 1.0);
        for (int i : bodySet.getBodyParticles(b)) {
            double sigma = std::sqrt(BOLTZ * temperature / bodySet.getMasses()[i]);
            double x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
            velocities[i] = Vec3(x, y, z) * sigma;
        }
        changed = true;
    }
    if (changed) {
        // The integrator's own change: it leaves forces valid, and the caller projects.
        inProjection = true;
        context->setVelocities(velocities);
        inProjection = false;
    }
}

void RigidBodyIntegrator::ensureForces() {
    if (!forcesAreValid || context->getLastForceGroups() != getIntegrationForceGroups())
        computeForces();
}

void RigidBodyIntegrator::computeForces() {
    context->calcForcesAndEnergy(true, false, getIntegrationForceGroups());
    forcesAreValid = true;
}

void RigidBodyIntegrator::endSteps() {
    saveRollbackState();
}
