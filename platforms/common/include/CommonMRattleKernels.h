#ifndef MRATTLE_COMMON_KERNELS_H_
#define MRATTLE_COMMON_KERNELS_H_

#include "internal/RigidBodyKernels.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeKernel.h"
#include <vector>

namespace MRattlePlugin {

/**
 * M-RATTLE on OpenMM's common compute platforms (OpenCL here, CUDA where built): the
 * step, projection and shapes run on the device, one work item per body. Body and
 * constraint atom lists are kept in the System's atom order and mapped to the device's
 * (reordered) atom order whenever OpenMM reorders atoms.
 */
class CommonIntegrateMRattleStepKernel : public IntegrateMRattleStepKernel {
public:
    CommonIntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc)
        : IntegrateMRattleStepKernel(name, platform), cc(cc) {
    }
    ~CommonIntegrateMRattleStepKernel() override;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
    void updateShapes(OpenMM::ContextImpl& context) override;
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override;
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override;
    double computeKineticEnergy(OpenMM::ContextImpl& context) override;
    bool isBodyLinear(int index) const override;
    int getBodyDegreesOfFreedom() const override;
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const override;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream) override;

private:
    class ReorderListener;
    /** Device atom indices of the bodies' atoms and the constraints' ends, after a reorder. */
    void mapAtoms();
    /** Throw, with the state put back to before the failed step, if the device recorded a failure. */
    void checkFailure();
    void setKernelArguments();
    /** Run the body projection (and free-constraint velocity step) on the Context's velocities. */
    void project(double tolerance, bool onlyIfNotRigid, bool collide, double kT);

    OpenMM::ComputeContext& cc;
    RigidBodyTopology topology;
    std::vector<int> systemBodyAtoms, systemConstraintAtoms;  // System atom indices, body-major / cluster-major
    std::vector<double> constraintDistances;
    std::vector<RigidBodyMath::Shape> shapes;
    int numBodies = 0, numClusters = 0;
    bool hasAndersen = false, argumentsSet = false;
    int stepsSinceFailureCheck = 0;
    OpenMM::ComputeArray bodyStart, bodyAtoms, bodyLinear, clusterStart, constraintAtoms, constraintDistance;
    OpenMM::ComputeArray newVelocity, failure;
    OpenMM::ComputeKernel kickAndDrift, resetBodies, constrainFreePositions, applyPositionStep, kickVelocities,
        projectBodies, constrainFreeVelocities;
};

} // namespace MRattlePlugin

#endif
