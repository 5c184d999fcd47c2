"""Drude particles' masses: the time step their spring allows.

A Drude particle's spring (k = q^2 / (4 pi eps0 alpha), about 4e5 kJ/mol/nm^2 in the CHARMM
Drude force fields) with OpenMM's 0.4 amu has omega h = 1.0 at 1 fs and 2.05 at 2 fs, past
velocity Verlet's limit of 2. A heavier Drude particle, its mass taken from its core, slows
the spring by sqrt(mass) and leaves every configurational average unchanged (masses do not
enter the Boltzmann weight of positions).
"""
import math

import openmm
from openmm import unit


def drudePairs(system):
    """(Drude particle, core) of every pair of the System's DrudeForces (none where OpenMM has no Drude plugin)."""
    drudeForce = getattr(openmm, 'DrudeForce', None)
    return [tuple(force.getParticleParameters(k)[:2]) for force in system.getForces()
            if drudeForce is not None and isinstance(force, drudeForce) for k in range(force.getNumParticles())]


def setDrudeMass(system, mass):
    """Give every Drude particle of the System's DrudeForces this mass (amu; a Quantity of mass
    or a number), taking the difference from its core so that each pair's mass is unchanged.
    Call it before the Context is made. Returns the number of Drude particles changed.

    With 1.6 amu the spring's omega h at 2 fs is what OpenMM's 0.4 amu gives at 1 fs."""
    value = mass.value_in_unit(unit.amu) if unit.is_quantity(mass) else float(mass)
    if not (math.isfinite(value) and value > 0):
        raise ValueError('setDrudeMass: the mass must be a finite number > 0 amu, got %r' % (mass,))
    pairs = drudePairs(system)
    if not pairs:
        raise ValueError('setDrudeMass: the System has no DrudeForce with Drude particles')
    masses = {}
    for drude, core in pairs:
        pair = (masses.get(drude, system.getParticleMass(drude).value_in_unit(unit.amu)) +
                masses.get(core, system.getParticleMass(core).value_in_unit(unit.amu)))
        if not value < pair:
            raise ValueError('setDrudeMass: %g amu would leave core particle %d without mass (its pair with Drude '
                             'particle %d has %g amu)' % (value, core, drude, pair))
        masses[drude], masses[core] = value, pair - value
    for particle, particleMass in masses.items():
        system.setParticleMass(particle, particleMass)
    return len(pairs)
