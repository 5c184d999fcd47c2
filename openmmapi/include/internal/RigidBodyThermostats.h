#ifndef MRATTLE_RIGID_BODY_THERMOSTATS_H_
#define MRATTLE_RIGID_BODY_THERMOSTATS_H_

#include "internal/RigidBodyState.h"
#include "internal/windowsExportMRattle.h"
#include <random>
#include <vector>

namespace MRattlePlugin {

/**
 * The thermostats' maths, written once for every platform's host side (the Reference and
 * CPU kernels use it directly; the device kernels mirror it and are tested against it).
 * Each thermostat acts on the whole kinetic energy K of the System's degrees of freedom
 * (the plugin's rule: RigidBodyTopology::getNumDegreesOfFreedom) by scaling every velocity
 * with one factor, which keeps rigid-body velocities rigid and free constraints satisfied.
 * kT is in kJ/mol, times in ps, frequencies in 1/ps.
 */
namespace RigidBodyThermostats {

/** The Yoshida-Suzuki orders the Nose-Hoover chain's factorisation supports. */
OPENMM_EXPORT_MRATTLE bool isSupportedYoshidaSuzukiOrder(int order);
/** Throws an OpenMMException naming the integrator unless chainLength >= 1, numMTS >= 1 and the order is supported. */
OPENMM_EXPORT_MRATTLE void requireChainSettings(const char* integratorName, int chainLength, int numMTS,
                                                int numYoshidaSuzuki);
/** The Yoshida-Suzuki weights of order 1, 3, 5 or 7 (they sum to 1); throws an OpenMMException otherwise. */
OPENMM_EXPORT_MRATTLE std::vector<double> yoshidaSuzukiWeights(int order);

/**
 * A Nose-Hoover chain (Martyna, Klein and Tuckerman 1992) coupled to the kinetic energy of
 * dof degrees of freedom: thermostat j has mass Q_1 = dof kT / w^2, Q_j = kT / w^2 (w the
 * collision frequency), position x_j and velocity v_j.
 */
struct OPENMM_EXPORT_MRATTLE NoseHooverChain {
    std::vector<double> positions, velocities;
    explicit NoseHooverChain(int length = 0) : positions(length, 0.0), velocities(length, 0.0) {
    }
    /**
     * Propagate the chain over time t (half a step in the integrators) by the Trotter
     * factorisation of Martyna, Tuckerman, Tobias and Klein (1996): numMTS sub-steps, each
     * split with the Yoshida-Suzuki weights. Returns the factor by which every velocity must
     * be scaled (the kinetic energy becomes factor^2 * kineticEnergy). With w = 0 the chain
     * does not move and the factor is exactly 1.
     */
    double propagate(double kineticEnergy, double dof, double kT, double frequency, double t, int numMTS,
                     const std::vector<double>& weights);
    /**
     * The heat bath's energy: sum_j Q_j v_j^2 / 2 + dof kT x_1 + kT sum_{j>1} x_j. With the
     * System's kinetic and potential energy it is the conserved quantity of the dynamics.
     */
    double energy(double dof, double kT, double frequency) const;
    /** The chain read from a State's integrator parameters ("chainPositions", "chainVelocities"). */
    static NoseHooverChain fromParameters(const IntegratorParameterValues& values);
};

/**
 * Stochastic velocity rescaling (Bussi, Donadio and Parrinello, J. Chem. Phys. 126, 014101,
 * 2007) over time t: the exact draw of the new kinetic energy of dof degrees of freedom,
 * K' = c K + (1 - c) Kbar (R_1^2 + S) / dof + 2 R_1 sqrt(c (1 - c) K Kbar / dof), with
 * Kbar = dof kT / 2, c = exp(-frequency t), R_1 standard normal and S the sum of dof - 1
 * squared standard normals, drawn as 2 Gamma((dof - 1) / 2) (the paper's appendix). Returns
 * the factor alpha that scales every velocity (alpha^2 K = K'; negative when the draw
 * turns the velocities over, as in the paper). Draws from the given stream (the
 * integrator's own). With frequency 0 the factor is exactly 1 and nothing is drawn.
 */
OPENMM_EXPORT_MRATTLE double csvrScale(double kineticEnergy, double dof, double kT, double frequency, double t,
                                       std::mt19937_64& random);

/** CSVR's accumulated work, read from a State's integrator parameters ("rescalingWork"). */
OPENMM_EXPORT_MRATTLE double csvrWork(const IntegratorParameterValues& values);

} // namespace RigidBodyThermostats
} // namespace MRattlePlugin

#endif
