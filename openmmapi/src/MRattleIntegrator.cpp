#include "MRattleIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/internal/ContextImpl.h"

using namespace MRattlePlugin;
using namespace OpenMM;

MRattleIntegrator::MRattleIntegrator(double stepSize) : RigidBodyIntegrator(IntegratorNames::MRattle) {
    setStepSize(stepSize);
}
