/*
 * RigidBodyMinimizer: the public facade. It checks the arguments, finds the rigid-body
 * integrator, and runs the search (RigidBodySearch) with the integrator's bodies.
 */
#include "RigidBodyMinimizer.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodySearch.h"
#include "openmm/CompoundIntegrator.h"
#include "openmm/OpenMMException.h"
#include <cmath>
#include <string>

using namespace MRattlePlugin;
using namespace OpenMM;

namespace {

RigidBodyIntegrator* findRigidBodyIntegrator(Integrator& integrator) {
    if (RigidBodyIntegrator* rigid = dynamic_cast<RigidBodyIntegrator*>(&integrator))
        return rigid;
    CompoundIntegrator* compound = dynamic_cast<CompoundIntegrator*>(&integrator);
    if (compound == nullptr)
        return nullptr;
    if (RigidBodyIntegrator* current = findRigidBodyIntegrator(compound->getIntegrator(compound->getCurrentIntegrator())))
        return current;
    for (int i = 0; i < compound->getNumIntegrators(); i++)
        if (RigidBodyIntegrator* member = findRigidBodyIntegrator(compound->getIntegrator(i)))
            return member;
    return nullptr;
}

} // namespace

bool RigidBodyMinimizer::appliesTo(Context& context) {
    return findRigidBodyIntegrator(context.getIntegrator()) != nullptr;
}

RigidBodyMinimizationReport RigidBodyMinimizer::minimize(Context& context, double tolerance, int maxIterations,
                                                         RigidBodyMinimizationReporter* reporter) {
    if (!(tolerance >= 0) || !std::isfinite(tolerance))
        throw OpenMMException(MinimizerPrefix + "the tolerance must be a finite number >= 0 (kJ/mol/nm), got " +
                              std::to_string(tolerance));
    if (maxIterations < 0)
        throw OpenMMException(MinimizerPrefix + "maxIterations must be >= 0 (0: until converged), got " +
                              std::to_string(maxIterations));
    RigidBodyIntegrator* integrator = findRigidBodyIntegrator(context.getIntegrator());
    if (integrator == nullptr)
        throw OpenMMException(MinimizerPrefix + "the Context's integrator is not one of the plugin's rigid-body "
                              "integrators (nor a CompoundIntegrator holding one); use OpenMM's LocalEnergyMinimizer");
    // A friend of the integrator: its ContextImpl, and its flag that defers the work of setPositions().
    RigidBodySearch search(context, *integrator->context, [integrator](bool on) { integrator->minimizing = on; },
                           integrator->getTopology(), integrator->getConstraintTolerance(), tolerance, maxIterations,
                           reporter);
    return search.run();
}
