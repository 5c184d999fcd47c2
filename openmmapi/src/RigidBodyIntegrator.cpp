#include "RigidBodyIntegrator.h"
#include "internal/OpenMMVersionCheck.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/CompoundIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <cmath>
#include <cstdint>
#include <sstream>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

namespace {

// The integrator's part of a checkpoint (OpenMM writes it after the Context's own data):
// magic, format version, the step kernel's name, the number of bodies in effect and their
// signature, then the kernel's own state. Numbers are native-endian, like the rest of an
// OpenMM checkpoint. Version 2: the kernel's state follows the header.
const char CheckpointMagic[8] = {'M', 'R', 'a', 't', 't', 'l', 'e', 'C'};
const int32_t CheckpointVersion = 2;
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

std::string hex(uint64_t value) {
    std::ostringstream text;
    text << "0x" << std::hex << value;
    return text.str();
}

/** The header's kernel name, printable whatever bytes a damaged checkpoint holds. */
std::string printable(const std::string& name) {
    std::string text;
    for (unsigned char c : name)
        text += (c >= 32 && c < 127 ? std::string(1, (char) c) : "\\x" + hex(c).substr(2));
    return text;
}

} // namespace

RigidBodyIntegrator::RigidBodyIntegrator() {
    setConstraintTolerance(1e-5);
}

int RigidBodyIntegrator::addRigidBody(const vector<int>& particles) {
    if (owner != nullptr)
        throw OpenMMException("addRigidBody: bodies cannot be added once the integrator is bound to a Context");
    RigidBodyTopology::checkBodyDefinition(declaredBodies.size(), particles);
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

const RigidBodyTopology& RigidBodyIntegrator::getTopology() const {
    requireContext();
    return topology;
}

const vector<vector<int> >& RigidBodyIntegrator::getBodiesInEffect() const {
    return getTopology().getBodies();
}

int RigidBodyIntegrator::getNumBodiesInEffect() const {
    return getTopology().getNumBodies();
}

bool RigidBodyIntegrator::isBodyLinear(int index) const {
    if (index < 0 || index >= getTopology().getNumBodies())
        throw OpenMMException("isBodyLinear: body index " + std::to_string(index) + " is out of range (" +
                              std::to_string(topology.getNumBodies()) + " bodies in effect)");
    return kernel.getAs<const RigidBodyKernel>().isBodyLinear(index);
}

const vector<int>& RigidBodyIntegrator::getFreeParticles() const {
    return getTopology().getFreeParticles();
}

int RigidBodyIntegrator::getNumDegreesOfFreedom() const {
    return getTopology().getNumDegreesOfFreedom(kernel.getAs<const RigidBodyKernel>().getNumLinearBodies());
}

void RigidBodyIntegrator::initialize(ContextImpl& contextRef) {
    if (owner != nullptr && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    checkOpenMMVersion(Platform::getOpenMMVersion());
    const System& system = contextRef.getSystem();
    topology = RigidBodyTopology(system, declaredBodies, contextRef.getMolecules());
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = contextRef.getPlatform().createKernel(getStepKernelName(), contextRef);
    kernel.getAs<RigidBodyKernel>().initialize(system, topology);
    forcesAreValid = false;
    velocitiesNeedProjection = false;
    lastStepCount = -1;
    refusedCheckpoint = false;
}

void RigidBodyIntegrator::cleanup() {
    kernel = Kernel();
}

vector<std::string> RigidBodyIntegrator::getKernelNames() {
    return {getStepKernelName()};
}

bool RigidBodyIntegrator::isCurrentIntegrator() const {
    const Integrator* integrator = &context->getIntegrator();
    // Members of a CompoundIntegrator (possibly nested) all hear stateChanged(); one steps.
    while (const CompoundIntegrator* compound = dynamic_cast<const CompoundIntegrator*>(integrator))
        integrator = &compound->getIntegrator(compound->getCurrentIntegrator());
    return integrator == this;
}

void RigidBodyIntegrator::stateChanged(State::DataType changed) {
    forcesAreValid = false;
    if (context == nullptr)
        return;
    RigidBodyKernel& stepKernel = kernel.getAs<RigidBodyKernel>();
    if (changed == State::Positions) {
        stepKernel.updateShapes(*context);
        positionsSetSinceRefusal = true;
    }
    if (changed == State::Velocities)
        velocitiesSetSinceRefusal = true;
    if (refusedCheckpoint && positionsSetSinceRefusal && velocitiesSetSinceRefusal)
        refusedCheckpoint = false;
    // Velocities the user sets are made rigid at once, so what the Context reports is what
    // the integrator uses; rigid ones (a checkpoint's, a saved State's) are kept bit for bit.
    if (changed == State::Positions || changed == State::Velocities) {
        if (isCurrentIntegrator())
            stepKernel.projectVelocities(*context, getConstraintTolerance());
        else
            velocitiesNeedProjection = true;
    }
}

void RigidBodyIntegrator::createCheckpoint(std::ostream& stream) const {
    requireContext();
    stream.write(CheckpointMagic, sizeof(CheckpointMagic));
    writeValue<int32_t>(stream, CheckpointVersion);
    const std::string kernelName = getStepKernelName();
    writeValue<int32_t>(stream, kernelName.size());
    stream.write(kernelName.data(), kernelName.size());
    writeValue<int32_t>(stream, topology.getNumBodies());
    writeValue<uint64_t>(stream, topology.getSignature());
    kernel.getAs<const RigidBodyKernel>().createCheckpoint(*context, stream);
}

void RigidBodyIntegrator::loadCheckpoint(std::istream& stream) {
    requireContext();
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
            throw OpenMMException("the checkpoint was written by an integrator using kernel '" + printable(kernelName) +
                                  "', and this one uses '" + getStepKernelName() +
                                  "': use saveState()/loadState() to change integrators");
        int32_t numBodies = readValue<int32_t>(stream, "number of rigid bodies");
        uint64_t signature = readValue<uint64_t>(stream, "rigid-body signature");
        if (numBodies != topology.getNumBodies() || signature != topology.getSignature())
            throw OpenMMException("the checkpoint was written with " + std::to_string(numBodies) +
                                  " rigid bodies in effect (signature " + hex(signature) + "), and this Context has " +
                                  std::to_string(topology.getNumBodies()) + " (signature " + hex(topology.getSignature()) +
                                  "): the bodies differ, so the System or the bodies declared with addRigidBody() are not "
                                  "those the checkpoint was written with");
        kernel.getAs<RigidBodyKernel>().loadCheckpoint(*context, stream);
    } catch (const OpenMMException& e) {
        // OpenMM has already overwritten positions, velocities, time, box and parameters.
        refusedCheckpoint = true;
        positionsSetSinceRefusal = velocitiesSetSinceRefusal = false;
        forcesAreValid = false;
        throw OpenMMException(std::string("loadCheckpoint: ") + e.what() +
                              ". The Context now holds part of that checkpoint's data (OpenMM reads it before the "
                              "integrator's part): set positions and velocities again, or load a checkpoint that fits, "
                              "before stepping");
    }
    refusedCheckpoint = false;
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
    return kernel.getAs<RigidBodyKernel>().getVelocitiesForTemperature(*context, temperature, randomSeed,
                                                                       getConstraintTolerance());
}

void RigidBodyIntegrator::step(int steps) {
    requireContext();
    if (getStepSize() == 0 || !std::isfinite(getStepSize()))
        throw OpenMMException("The step size must be a finite nonzero number of picoseconds, got " +
                              std::to_string(getStepSize()));
    if (refusedCheckpoint)
        throw OpenMMException("step: the last loadCheckpoint() was refused and left part of that checkpoint's data in "
                              "the Context; set positions and velocities again, or load a checkpoint that fits, before "
                              "stepping");
    RigidBodyKernel& stepKernel = kernel.getAs<RigidBodyKernel>();
    for (int i = 0; i < steps; i++) {
        // Another integrator (of a CompoundIntegrator) stepped since this one did, or
        // velocities were set while it was not current: this integrator's bodies decide
        // now, before a thermostat's collisions (which the kernel must see as such).
        if (context->getStepCount() != lastStepCount || velocitiesNeedProjection) {
            forcesAreValid = false;
            stepKernel.projectVelocities(*context, getConstraintTolerance());
            velocitiesNeedProjection = false;
        }
        if (context->updateContextState())
            forcesAreValid = false;
        // A getState() may have overwritten the forces with other force groups.
        if (context->getLastForceGroups() != getIntegrationForceGroups())
            forcesAreValid = false;
        stepKernel.execute(*context, *this, forcesAreValid);
        lastStepCount = context->getStepCount();
    }
}
