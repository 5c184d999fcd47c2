"""Shared pieces of the benchmark suite: integrators by name, NVE runs, test molecules, rigid water,
block statistics, CSV files and figures."""
import csv
import functools
import math
import os
import subprocess
import time

import numpy as np
import openmm
from openmm import unit

import mrattle

FS = 0.001  # ps
KB = 0.00831446261815324  # kJ/mol/K
TEMPERATURE = 300.0  # K, the water studies'


def context(system, integrator, positions, velocities=None, platform_name="CPU", threads=None):
    """A Context at `positions` with `velocities`: an array, or (temperature, seed) for thermal ones; on CPU,
    `threads` threads (a fixed count for reproducible timings)."""
    c = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(platform_name),
                       {"Threads": str(threads)} if platform_name == "CPU" and threads is not None else {})
    c.setPositions(positions)
    if isinstance(velocities, tuple):
        c.setVelocitiesToTemperature(*velocities)
    elif velocities is not None:
        c.setVelocities(velocities)
    return c


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


def nve_run(system, positions, velocities, method, step_ps, total_ps, sample_ps, platform_name="CPU",
            bodies=None, threads=1, tolerance=1e-10):
    """Run NVE and sample the energies (and rigidity): a dict of arrays, the wall time, the Context; a blow-up (a
    non-finite energy or an OpenMM exception) ends the run and is reported in 'failure'."""
    integrator = make_integrator(method, step_ps, tolerance, bodies)
    context_ = context(system, integrator, positions, velocities, platform_name, threads)
    stride = max(1, int(round(sample_ps / step_ps)))
    samples = max(1, int(round(total_ps / (stride * step_ps))))
    dof = mrattle.degreesOfFreedom(context_)
    times, kinetic, potential, rigidity = [], [], [], []
    reference = failure = None
    start = time.perf_counter()
    for k in range(samples + 1):
        if k > 0:
            try:
                integrator.step(stride)
            except Exception as error:  # OpenMM's constraint failures arrive as exceptions
                failure = str(error).splitlines()[0]
                break
        state = context_.getState(getEnergy=True, getPositions=bodies is not None)
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
            x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)  # every intra-body distance
            d = np.concatenate([np.linalg.norm(x[b][:, None] - x[b], axis=2)[np.triu_indices(len(b), 1)]
                                for b in bodies] or [np.zeros(0)])
            if reference is None:
                reference = d
            rigidity.append(float(np.max(np.abs(d - reference))) if d.size else 0.0)
    wall = time.perf_counter() - start
    kinetic, potential = np.array(kinetic), np.array(potential)
    return {"time": np.array(times), "kinetic": kinetic, "potential": potential, "total": kinetic + potential,
            "rigidity": np.array(rigidity), "dof": dof, "wall": wall, "steps": len(times) and (len(times) - 1) * stride,
            "failure": failure, "context": context_, "integrator": integrator}


# All 10 pair distances of the 5-site molecule, ordered so that the first 9 (the centre-site
# pair 0-1 left out) are a set OpenMM 7.7's CCMA converges on (some other sets of 9 make its
# velocity iteration diverge; the accuracy part's Verlet + CCMA rows run on this one).
TETRAHEDRAL_PAIRS = [(0, 2), (0, 3), (0, 4), (1, 2), (1, 3), (1, 4), (2, 3), (2, 4), (3, 4), (0, 1)]


def tetrahedral_cluster(num_per_side=3, spacing=0.55, seed=7, constraints=None):
    """N^3 rigid tetrahedral molecules in vacuum with LJ + charges between molecules, and `constraints` of their
    pair distances as System constraints (9: rigid for OpenMM's algorithms; 10: all): (system, positions, bodies)."""
    # A non-planar 5-site rigid molecule (centre + 4 distorted tetrahedral sites), nm and daltons.
    sites = np.array([[0.0, 0.0, 0.0], [0.109, 0.0, 0.0], [-0.036, 0.103, 0.0],
                      [-0.036, -0.051, 0.089], [-0.036, -0.052, -0.090]])
    masses = np.array([12.011, 1.008, 14.007, 15.999, 32.06])
    sites = sites - masses.dot(sites) / masses.sum()
    charges = np.array([0.2, 0.1, -0.3, -0.2, 0.2])
    lj = [(0.34, 0.36), (0.25, 0.13), (0.325, 0.71), (0.30, 0.88), (0.36, 1.05)]
    rng = np.random.default_rng(seed)
    system = openmm.System()
    nb = openmm.NonbondedForce()
    nb.setNonbondedMethod(openmm.NonbondedForce.NoCutoff)
    positions, bodies, pairs = [], [], TETRAHEDRAL_PAIRS
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
    try:
        with open("/proc/cpuinfo") as f:
            model = next(line.split(":", 1)[1].strip() for line in f if line.startswith("model name"))
    except (OSError, StopIteration):
        model = "unknown CPU"
    return "%s, %d cores visible, OpenMM %s" % (model, os.cpu_count() or 0, openmm.Platform.getOpenMMVersion())


@functools.lru_cache(maxsize=None)
def git_commit():
    """The checkout's commit (short) at the first call (a run makes it at its start), which every results
    stamp names; "unknown" outside a git checkout or without git (a `git archive` copy, as in scripts/test-openmm8.sh)."""
    try:
        done = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=os.path.dirname(os.path.abspath(__file__)))
    except OSError:
        return "unknown"
    return done.stdout.strip() or "unknown"


def interleaved(integrators, steps, batches):
    """Seconds per step of each integrator in `batches` rounds that interleave them, so that all share the
    machine's load. integrators: {name: integrator}; steps: {name: steps per batch}."""
    seconds = {name: [] for name in integrators}
    for _ in range(batches):
        for name, integrator in integrators.items():
            start = time.perf_counter()
            integrator.step(steps[name])
            seconds[name].append((time.perf_counter() - start) / steps[name])
    return seconds


def masses(system):
    """The particles' masses (daltons)."""
    return np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])


def block_mean(values, blocks=10):
    """Mean and its standard error from block averages."""
    values = np.asarray(values, dtype=float)
    n = len(values) // blocks
    means = values[:n * blocks].reshape(blocks, n).mean(axis=1)
    return means.mean(), means.std(ddof=1) / math.sqrt(blocks)


def write_csv(path, rows, columns=None):
    """Rows as CSV: every column any row has, in first-seen order (or `columns`); live objects (an NVE
    run's Context and Integrator) dropped."""
    if not rows and not columns:
        return
    plain = (str, int, float, bool, tuple, list, type(None))
    rows = [{k: v for k, v in r.items() if isinstance(v, plain) or hasattr(v, "dtype")} for r in rows]
    keys = list(columns or [])
    for r in rows if columns is None else []:
        keys += [k for k in r if k not in keys]
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=keys, restval="", extrasaction="ignore")
        w.writeheader()
        w.writerows(rows)


def read_csv(path, text=("method", "model", "failure")):
    """A CSV's rows, numbers as floats but the `text` columns, empty cells dropped."""
    with open(path) as f:
        return [{k: (v if k in text else float(v)) for k, v in r.items() if v != ""} for r in csv.DictReader(f)]


def panels(count, width=5.2, height=4.2):
    """A figure of `count` plots side by side (matplotlib without a display): (figure, axes)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(1, count, figsize=(width * count, height), squeeze=False)
    return fig, axes[0]


def save_figure(fig, path, title=None):
    import matplotlib.pyplot as plt
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def water(pdb_name="tip3p.pdb", forcefield_name="amber14/tip3p.xml", barostat_seed=None):
    """A rigid water box of OpenMM's app/data with PME (0.9 nm), its waters at the model's exact geometry
    (SETTLE through applyConstraints: M-RATTLE keeps the shapes it is given), and the bodies; with a
    MonteCarloBarostat (1 bar, 300 K, every 25 steps) if a barostat_seed is given (0: OpenMM picks one)."""
    from openmm import app
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", pdb_name))
    system = app.ForceField(forcefield_name).createSystem(pdb.topology, nonbondedMethod=app.PME,
                                                          nonbondedCutoff=0.9 * unit.nanometers, rigidWater=True)
    if barostat_seed is not None:
        barostat = openmm.MonteCarloBarostat(1 * unit.bar, TEMPERATURE * unit.kelvin, 25)
        barostat.setRandomNumberSeed(barostat_seed)
        system.addForce(barostat)
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(pdb.positions)
    context.applyConstraints(1e-12)
    return system, context.getState(getPositions=True).getPositions(), mrattle.rigidBodies(pdb.topology, system)


def equilibrate(system, positions, ps, threads, seed=11):
    """LangevinMiddle + SETTLE at 300 K, 1/ps, 2 fs: the start of every run of a water study (no barostat: the
    runs start in the System's default box)."""
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE * unit.kelvin, 1 / unit.picosecond, 2 * unit.femtoseconds)
    integrator.setRandomNumberSeed(seed)
    c = context(system, integrator, positions, (TEMPERATURE * unit.kelvin, seed), "CPU", threads)
    integrator.step(int(round(ps / 0.002)))
    state = c.getState(getPositions=True, getVelocities=True)
    return state.getPositions(asNumpy=True), state.getVelocities(asNumpy=True)


def water_integrator(method, step_fs, seed=5, thermostat_frequency=10.0):
    """The water studies' integrators by name, at 300 K (the thermostats 10/ps, the Langevin ones 1/ps)."""
    step = step_fs * unit.femtoseconds
    if method in ("M-RATTLE", "M-RATTLE NVE"):
        return mrattle.MRattleIntegrator(step)
    if method == "Verlet + SETTLE":
        return openmm.VerletIntegrator(step)
    if method == "M-RATTLE Nose-Hoover chain":
        return mrattle.MRattleNoseHooverIntegrator(TEMPERATURE, thermostat_frequency, step)
    integrator = {"M-RATTLE CSVR": lambda: mrattle.MRattleBussiIntegrator(TEMPERATURE, thermostat_frequency, step),
                  "LangevinMiddle + SETTLE": lambda: openmm.LangevinMiddleIntegrator(TEMPERATURE, 1.0, step),
                  "M-RATTLE Langevin": lambda: mrattle.MRattleLangevinIntegrator(TEMPERATURE, 1.0, step)}[method]()
    integrator.setRandomNumberSeed(seed)
    return integrator


def rigid_split(velocities, masses, bodies, positions=None):
    """Translational and rotational kinetic energy of equal-size bodies (kJ/mol): 1/2 M V^2 per body and the
    rest, sum m |v - V|^2 / 2, the formula RigidBodyIntegrator.computeTranslationalKineticEnergy() uses; given
    the positions, each body's velocities are first made rigid there (the mass-weighted projection, RATTLE's
    velocity step: the identity for velocities that are rigid already)."""
    index = np.asarray(bodies)
    m = masses[index]
    mass = m.sum(axis=1)
    v = velocities[index]
    V = (m[..., None] * v).sum(axis=1) / mass[:, None]
    relative = v - V[:, None, :]
    if positions is not None:
        x = positions[index]
        a = x - ((m[..., None] * x).sum(axis=1) / mass[:, None])[:, None, :]
        L = (m[..., None] * np.cross(a, relative)).sum(axis=1)
        J = np.einsum("bk,bki,bkj->bij", m, a, a)
        inertia = np.trace(J, axis1=1, axis2=2)[:, None, None] * np.eye(3) - J
        relative = np.cross(np.linalg.solve(inertia, L[..., None])[..., 0][:, None, :], a)
    return 0.5 * np.sum(mass * (V * V).sum(axis=1)), 0.5 * np.sum(m * (relative * relative).sum(axis=2))


def temperatures(velocities, masses, bodies, removes_cm, positions=None):
    """Translational and rotational temperature of rigid bodies (3 degrees of freedom each per body, a
    CMMotionRemover's 3 taken from the translations), from rigid_split."""
    kt, kr = rigid_split(velocities, masses, bodies, positions)
    return 2 * kt / ((3 * len(bodies) - (3 if removes_cm else 0)) * KB), 2 * kr / (3 * len(bodies) * KB)


def density(state, masses):
    """g/mL, from a rectangular box."""
    a, b, c = state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
    return masses.sum() * 1.66053906660e-24 / (a[0] * b[1] * c[2] * 1e-21)


def removes_cm(system):
    return any(isinstance(f, openmm.CMMotionRemover) for f in system.getForces())
