#ifndef MRATTLE_COMMON_KERNELS_H_
#define MRATTLE_COMMON_KERNELS_H_

#include "BodyShapeConstraints.h"
#include "CommonBodyKineticEnergy.h"
#include "internal/RigidBodyKernels.h"
#include "mrattle/RigidBodyMath.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeKernel.h"
#include <memory>
#include <vector>

namespace MRattlePlugin {

/**
 * M-RATTLE (MRattleIntegrator) and Langevin dynamics with M-RATTLE
 * (MRattleLangevinIntegrator) on OpenMM's common compute platforms (OpenCL here, CUDA
 * where built): the step, projection and shapes run on the device, one work item per body.
 * One class serves both kernel names (the integrator tells which step to take). Body and
 * constraint atom lists are kept in the System's atom order and mapped to the device's
 * (reordered) atom order whenever OpenMM reorders atoms.
 */
class CommonIntegrateMRattleStepKernel : public RigidBodyKernel {
public:
    CommonIntegrateMRattleStepKernel(const std::string& name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc)
        : RigidBodyKernel(name, platform), cc(cc) {
    }
    ~CommonIntegrateMRattleStepKernel() override;
    void initialize(const OpenMM::System& system, const RigidBodyTopology& topology,
                    const RigidBodyIntegrator& integrator) override;
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator, bool& forcesAreValid) override;
    void updateShapes(OpenMM::ContextImpl& context) override;
    void projectVelocities(OpenMM::ContextImpl& context, double tolerance) override;
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(OpenMM::ContextImpl& context, double temperature,
                                                          int randomSeed, double tolerance) override;
    double computeKineticEnergy(OpenMM::ContextImpl& context) override;
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational,
                                double& free) override;
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
    /** A kick over kickTime, a drift over h, the resets and free constraints, written unless something failed. */
    void driftAndReset(double kickTime, double h, double tolerance, int step);
    /** A kick of the Context's velocities over kickTime. */
    void kick(double kickTime);
    void setMixedArg(OpenMM::ComputeKernel& kernel, int index, double value);

    OpenMM::ComputeContext& cc;
    RigidBodyTopology topology;
    std::vector<int> systemBodyAtoms, systemConstraintAtoms;  // System atom indices, body-major / cluster-major
    std::vector<double> constraintDistances;
    std::vector<RigidBodyMath::Shape> shapes;
    int numBodies = 0, numClusters = 0;
    bool hasAndersen = false, argumentsSet = false;
    int stepsSinceFailureCheck = 0;
    OpenMM::ComputeArray bodyStart, bodyAtoms, bodyLinear, clusterStart, constraintAtoms, constraintDistance;
    OpenMM::ComputeArray newVelocity, failure, posqBackup, correctionBackup, velmBackup;
    OpenMM::ComputeKernel kickAndDrift, resetBodies, constrainFreePositions, applyPositionStep, kickVelocities,
        projectBodies, constrainFreeVelocities, langevinNoise, backupState;
    bool langevin = false;
    std::unique_ptr<BodyShapeConstraints> shapeConstraints;
    std::unique_ptr<CommonBodyKineticEnergy> bodyKineticEnergy;  // after the arrays it reads
};

} // namespace MRattlePlugin

#endif
