#include "MRattleLangevinIntegrator.h"
#include "internal/RigidBodyKernels.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

// The kernel interface's key function: its vtable and type information live in this
// library only, so Kernel::getAs<> casts agree across the plugin's shared libraries.
IntegrateMRattleLangevinStepKernel::~IntegrateMRattleLangevinStepKernel() {
}

MRattleLangevinIntegrator::MRattleLangevinIntegrator(double temperature, double frictionCoeff, double stepSize) {
    setTemperature(temperature);
    setFriction(frictionCoeff);
    setStepSize(stepSize);
}

void MRattleLangevinIntegrator::setTemperature(double value) {
    requireNonNegativeSetting("MRattleLangevinIntegrator", "temperature", "K", value);
    temperature = value;
}

void MRattleLangevinIntegrator::setFriction(double coeff) {
    requireNonNegativeSetting("MRattleLangevinIntegrator", "friction", "/ps", coeff);
    friction = coeff;
}

std::string MRattleLangevinIntegrator::getStepKernelName() const {
    return IntegrateMRattleLangevinStepKernel::Name();
}

void MRattleLangevinIntegrator::executeStep(Kernel& kernel, ContextImpl& context, bool& forcesAreValid) {
    kernel.getAs<IntegrateMRattleLangevinStepKernel>().execute(context, *this, forcesAreValid);
}
