#include "HostRigidBodyRules.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <cstdint>
#include <istream>
#include <ostream>
#include <random>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

void HostRigidBodyRules::requireFinite(const vector<Vec3>& values, const std::string& what) {
    for (size_t i = 0; i < values.size(); i++)
        if (!std::isfinite(values[i][0] + values[i][1] + values[i][2]))
            throw OpenMMException("the " + what + " of particle " + std::to_string(i) + " is not finite");
}

vector<RigidBodyMath::Shape> HostRigidBodyRules::classifyShapes(const RigidBodyTopology& topology,
                                                                const vector<Vec3>& positions) {
    const double* x = reinterpret_cast<const double*>(positions.data());
    vector<RigidBodyMath::Shape> shapes(topology.getNumBodies());
    for (int b = 0; b < topology.getNumBodies(); b++) {
        const vector<int>& atoms = topology.getBodyParticles(b);
        RigidBodyMath::BodyView body{atoms.data(), (int) atoms.size(), topology.getMasses().data(),
                                     topology.getBodyMass(b), false};
        Eigen::Vector3d center = RigidBodyMath::centerOfMass(body, x);
        shapes[b] = RigidBodyMath::classifyShape(RigidBodyMath::secondMoment(body, x, center), body.totalMass);
    }
    return shapes;
}

int HostRigidBodyRules::bodyDegreesOfFreedom(const vector<RigidBodyMath::Shape>& shapes) {
    int dof = 0;
    for (RigidBodyMath::Shape shape : shapes)
        dof += RigidBodyMath::degreesOfFreedom(shape);
    return dof;
}

vector<Vec3> HostRigidBodyRules::maxwellBoltzmannVelocities(const vector<double>& inverseMasses, double temperature,
                                                            int randomSeed) {
    std::mt19937_64 generator(randomSeed);
    std::normal_distribution<double> gaussian(0.0, 1.0);
    vector<Vec3> velocities(inverseMasses.size(), Vec3());
    for (size_t i = 0; i < inverseMasses.size(); i++)
        if (inverseMasses[i] != 0) {
            const double scale = std::sqrt(BOLTZ * temperature * inverseMasses[i]);
            const double x = gaussian(generator), y = gaussian(generator), z = gaussian(generator);
            velocities[i] = Vec3(x, y, z) * scale;
        }
    return velocities;
}

void HostRigidBodyRules::scaleToTemperature(const RigidBodyTopology& topology, const vector<double>& inverseMasses,
                                            int degreesOfFreedom, double temperature, vector<Vec3>& velocities) {
    const vector<double>& masses = topology.getMasses();
    double totalMass = 0;
    Vec3 momentum;
    for (size_t i = 0; i < velocities.size(); i++) {
        totalMass += masses[i];
        momentum += velocities[i] * masses[i];
    }
    if (topology.removesCenterOfMassMotion() && totalMass > 0) {
        const Vec3 centerVelocity = momentum / totalMass;
        for (size_t i = 0; i < velocities.size(); i++)
            if (inverseMasses[i] != 0)
                velocities[i] -= centerVelocity;
    }
    double kinetic = 0;
    for (size_t i = 0; i < velocities.size(); i++)
        if (inverseMasses[i] != 0)
            kinetic += 0.5 * velocities[i].dot(velocities[i]) / inverseMasses[i];
    if (kinetic > 0 && degreesOfFreedom > 0) {
        const double scale = std::sqrt(0.5 * degreesOfFreedom * BOLTZ * temperature / kinetic);
        for (Vec3& v : velocities)
            v *= scale;
    }
}

void HostRigidBodyRules::writeKernelState(std::ostream& stream, const std::string& state) {
    const int32_t length = state.size();
    stream.write(reinterpret_cast<const char*>(&length), sizeof(length));
    stream.write(state.data(), length);
}

std::string HostRigidBodyRules::readKernelState(std::istream& stream) {
    int32_t length = -1;
    stream.read(reinterpret_cast<char*>(&length), sizeof(length));
    if (!stream || stream.gcount() != (std::streamsize) sizeof(length))
        throw OpenMMException("the checkpoint is truncated (it ends before the kernel's state)");
    if (length < 0 || length > (1 << 20))
        throw OpenMMException("the checkpoint's kernel data is malformed (a state of length " + std::to_string(length) +
                              ")");
    std::string state(length, ' ');
    stream.read(&state[0], length);
    if (!stream || stream.gcount() != length)
        throw OpenMMException("the checkpoint is truncated (it ends in the kernel's state)");
    return state;
}
