#include "RigidSplittingIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;

RigidSplittingIntegrator::RigidSplittingIntegrator(double stepSize)
    : RigidBodyIntegrator(IntegratorNames::RigidSplitting) {
    setStepSize(stepSize);
}
