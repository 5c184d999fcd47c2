"""Shared pieces of the benchmark suite: integrators by name, NVE runs, test molecules."""
import math
import time

import numpy as np
import openmm
from openmm import unit

import mrattle

FS = 0.001  # ps


def platform(name, threads=None):
    """An OpenMM platform and its properties (CPU: fixed thread count for reproducible timings)."""
    properties = {}
    if name == "CPU" and threads is not None:
        properties["Threads"] = str(threads)
    return openmm.Platform.getPlatformByName(name), properties


def make_integrator(method, step_ps, tolerance=1e-10, bodies=None):
    """Integrators compared in the suite, by name; the plugin's get `bodies` declared."""
    if method in ("M-RATTLE", "splitting"):
        integrator = (mrattle.MRattleIntegrator if method == "M-RATTLE" else mrattle.RigidSplittingIntegrator)(step_ps)
        for body in bodies or []:
            integrator.addRigidBody(body)
        return integrator
    if method == "RATTLE (CustomIntegrator)":
        return mrattle.baselines.rattleVerletIntegrator(step_ps, tolerance)
    if method == "Verlet + CCMA":
        integrator = openmm.VerletIntegrator(step_ps)
        integrator.setConstraintTolerance(tolerance)
        return integrator
    raise ValueError("unknown method %r" % method)


def intra_distances(positions, bodies):
    """All intra-body pair distances, concatenated (for rigidity checks)."""
    out = []
    for body in bodies:
        p = positions[body]
        d = p[:, None, :] - p[None, :, :]
        iu = np.triu_indices(len(body), 1)
        out.append(np.sqrt((d ** 2).sum(-1))[iu])
    return np.concatenate(out) if out else np.zeros(0)


def nve_run(system, positions, velocities, method, step_ps, total_ps, sample_ps, platform_name="CPU",
            bodies=None, threads=1, tolerance=1e-10, progress=None):
    """Run NVE and sample total energy; returns a dict of arrays and the wall time.

    Raises nothing on a blow-up: a non-finite energy or an OpenMM exception ends the run
    and is reported in 'failure'.
    """
    integrator = make_integrator(method, step_ps, tolerance, bodies)
    plat, props = platform(platform_name, threads)
    context = openmm.Context(system, integrator, plat, props)
    context.setPositions(positions)
    if velocities is not None:
        context.setVelocities(velocities)
    stride = max(1, int(round(sample_ps / step_ps)))
    samples = max(1, int(round(total_ps / (stride * step_ps))))
    dof = mrattle.degreesOfFreedom(context)
    times, kinetic, potential, rigidity = [], [], [], []
    reference = None
    failure = None
    start = time.perf_counter()
    for k in range(samples + 1):
        if k > 0:
            try:
                integrator.step(stride)
            except Exception as error:  # OpenMM's constraint failures arrive as exceptions
                failure = str(error).splitlines()[0]
                break
        state = context.getState(getEnergy=True, getPositions=bodies is not None)
        ke = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        pe = state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        if not (math.isfinite(ke) and math.isfinite(pe)):
            failure = "energy not finite after %d steps (last finite kinetic energy %.3g kJ/mol)" % (
                k * stride, kinetic[-1] if kinetic else float("nan"))
            break
        times.append(state.getTime().value_in_unit(unit.picosecond))
        kinetic.append(ke)
        potential.append(pe)
        if bodies is not None:
            d = intra_distances(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer), bodies)
            if reference is None:
                reference = d
            rigidity.append(float(np.max(np.abs(d - reference))) if d.size else 0.0)
        if progress:
            progress(k, samples)
    wall = time.perf_counter() - start
    kinetic = np.array(kinetic)
    potential = np.array(potential)
    return {
        "time": np.array(times), "kinetic": kinetic, "potential": potential, "total": kinetic + potential,
        "rigidity": np.array(rigidity), "dof": dof, "wall": wall, "steps": len(times) and (len(times) - 1) * stride,
        "failure": failure, "context": context, "integrator": integrator,
    }


def tetrahedral_sites():
    """A non-planar 5-site rigid molecule (centre + 4 distorted tetrahedral sites), nm and daltons."""
    sites = np.array([[0.0, 0.0, 0.0], [0.109, 0.0, 0.0], [-0.036, 0.103, 0.0],
                      [-0.036, -0.051, 0.089], [-0.036, -0.052, -0.090]])
    masses = np.array([12.011, 1.008, 14.007, 15.999, 32.06])
    return sites - masses.dot(sites) / masses.sum(), masses


# All 10 pair distances of the 5-site molecule, ordered so that the first 9 (the centre-site
# pair 0-1 left out) are a set OpenMM 7.7's CCMA converges on: leaving out 0-2, 0-3, 0-4,
# 2-3, 2-4 or 3-4 instead makes its velocity iteration diverge (accuracy.ccma_subsets()).
TETRAHEDRAL_PAIRS = [(0, 2), (0, 3), (0, 4), (1, 2), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4), (0, 1)]


def tetrahedral_cluster(num_per_side=3, spacing=0.55, seed=7, constraints=None, temperature=200.0):
    """N^3 rigid tetrahedral molecules in vacuum with LJ + charges between molecules.

    constraints: None, or the number of intra-molecular pair distances to declare as
    System constraints (9 makes it rigid for OpenMM's own algorithms; 10 is all pairs).
    Returns (system, positions, bodies).
    """
    sites, masses = tetrahedral_sites()
    charges = np.array([0.2, 0.1, -0.3, -0.2, 0.2])
    lj = [(0.34, 0.36), (0.25, 0.13), (0.325, 0.71), (0.30, 0.88), (0.36, 1.05)]
    rng = np.random.default_rng(seed)
    system = openmm.System()
    nb = openmm.NonbondedForce()
    nb.setNonbondedMethod(openmm.NonbondedForce.NoCutoff)
    positions, bodies = [], []
    pairs = TETRAHEDRAL_PAIRS
    for a in range(num_per_side):
        for b in range(num_per_side):
            for c in range(num_per_side):
                q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
                if np.linalg.det(q) < 0:
                    q[:, 0] *= -1
                centre = np.array([a, b, c]) * spacing
                first = system.getNumParticles()
                for s in range(5):
                    system.addParticle(masses[s])
                    nb.addParticle(charges[s], lj[s][0], lj[s][1])
                    positions.append(centre + q.dot(sites[s]))
                body = list(range(first, first + 5))
                bodies.append(body)
                for i, j in pairs:
                    nb.addException(first + i, first + j, 0, 1, 0)
                if constraints:
                    for i, j in pairs[:constraints]:
                        dist = float(np.linalg.norm(sites[i] - sites[j]))
                        system.addConstraint(first + i, first + j, dist)
    system.addForce(nb)
    positions = np.array(positions)
    positions -= positions.mean(axis=0)
    return system, positions, bodies


def rigid_velocities(system, positions, bodies, temperature, seed=1, box=None):
    """Rigid-body Maxwell-Boltzmann velocities at exactly `temperature` (via M-RATTLE's projection)."""
    integrator = mrattle.MRattleIntegrator(0.001)
    for body in bodies:
        integrator.addRigidBody(body)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    if box is not None:
        context.setPeriodicBoxVectors(*box)
    context.setPositions(positions)
    context.setVelocitiesToTemperature(temperature, seed)
    return context.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(
        unit.nanometer / unit.picosecond)


def machine_description():
    """CPU model and core count, for the results page."""
    model = "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    model = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    import os
    return "%s, %d cores visible, OpenMM %s" % (model, os.cpu_count() or 0, openmm.Platform.getOpenMMVersion())


def benzene_bodies(num_particles):
    """The bodies of the benzene models (12 consecutive atoms per molecule)."""
    return [list(range(12 * m, 12 * m + 12)) for m in range(num_particles // 12)]


def interleaved_median(integrators, steps, batches):
    """Median seconds per step of each integrator, timed in `batches` rounds that interleave them so
    all share the machine's load. integrators: {name: integrator}; steps: {name: steps per batch}."""
    import statistics
    seconds = {name: [] for name in integrators}
    for _ in range(batches):
        for name, integrator in integrators.items():
            start = time.perf_counter()
            integrator.step(steps[name])
            seconds[name].append((time.perf_counter() - start) / steps[name])
    return {name: statistics.median(values) for name, values in seconds.items()}
