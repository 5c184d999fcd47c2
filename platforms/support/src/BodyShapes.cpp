#include "BodyShapes.h"

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

vector<RigidBodyMath::Shape> BodyShapes::classify(const RigidBodyTopology& topology, const vector<Vec3>& positions) {
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

int BodyShapes::degreesOfFreedom(const vector<RigidBodyMath::Shape>& shapes) {
    int dof = 0;
    for (RigidBodyMath::Shape shape : shapes)
        dof += RigidBodyMath::degreesOfFreedom(shape);
    return dof;
}
