#include "CommonBodyKineticEnergy.h"
#include "CommonMRattleKernelSources.h"
#include "openmm/common/ContextSelector.h"
#include "openmm/common/IntegrationUtilities.h"
#include <vector>

using namespace MRattlePlugin;
using namespace OpenMM;
using std::vector;

CommonBodyKineticEnergy::CommonBodyKineticEnergy(ComputeContext& cc, int numBodies, ComputeArray& bodyStart,
                                                 ComputeArray& bodyAtoms)
    : cc(cc), numBodies(numBodies), bodyStart(bodyStart), bodyAtoms(bodyAtoms) {
}

void CommonBodyKineticEnergy::compute(double& translational, double& rotational, double& free) {
    ContextSelector selector(cc);
    const double total = cc.getIntegrationUtilities().computeKineticEnergy(0.0);
    translational = rotational = 0;
    double bodies = 0;
    if (numBodies > 0) {
        const bool doubleMixed = cc.getUseDoublePrecision() || cc.getUseMixedPrecision();
        if (!kernel) {
            energies.initialize(cc, 3 * numBodies, doubleMixed ? sizeof(double) : sizeof(float), "mrattleBodyEnergies");
            kernel = cc.compileProgram(CommonMRattleKernelSources::bodyKineticEnergy)->createKernel("bodyKineticEnergy");
            kernel->addArg(numBodies);
            kernel->addArg(bodyStart);
            kernel->addArg(bodyAtoms);
            kernel->addArg(cc.getVelm());
            kernel->addArg(energies);
        }
        kernel->execute(numBodies);
        vector<double> values(3 * numBodies);
        if (doubleMixed)
            energies.download(values);
        else {
            vector<float> single(3 * numBodies);
            energies.download(single);
            values.assign(single.begin(), single.end());
        }
        for (int b = 0; b < numBodies; b++) {
            translational += values[3 * b];
            rotational += values[3 * b + 1];
            bodies += values[3 * b + 2];
        }
    }
    free = total - bodies;
}
