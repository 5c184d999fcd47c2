"""Cost per step on the paper's own systems: one rigid benzene and the 27-benzene cluster
(forces included: the models' Lennard-Jones and Coulomb sites, no cutoff), M-RATTLE against
the splitting method, on the Reference platform and the CPU platform with one thread."""
import time

import numpy as np
from openmm import unit

import mrattle
from . import common


def _start(model):
    """(positions, rigid velocities at 300 K, bodies) of a model: one start for every run of it."""
    bodies = common.benzene_bodies(model.system.getNumParticles())
    x = np.array(model.positions.value_in_unit(unit.nanometer))
    return x, common.rigid_velocities(model.system, x, bodies, 300.0, seed=2), bodies


def _context(model, initial, method, platform_name):
    """(integrator, context): the caller keeps both, or the Context is freed."""
    import openmm
    x, v, bodies = initial
    integrator = common.make_integrator(method, 2 * common.FS, bodies=bodies)
    plat, props = common.platform(platform_name, 1)
    context = openmm.Context(model.system, integrator, plat, props)
    context.setPositions(x)
    context.setVelocities(v)
    return integrator, context


def compare(platforms, batches, batch_seconds, log):
    """Median time per 2 fs step of each method, interleaved batches; rows per system, platform, method."""
    models = {"isolated benzene": mrattle.models.benzene(),
              "27-benzene cluster": mrattle.models.benzeneCluster(temperature=250 * unit.kelvin, seed=1)}
    rows = []
    for label, model in models.items():
        initial = _start(model)
        for platform_name in platforms:
            contexts = {m: _context(model, initial, m, platform_name) for m in ("M-RATTLE", "splitting")}
            runs = {m: pair[0] for m, pair in contexts.items()}
            steps = {}
            for method, integrator in runs.items():
                integrator.step(10)
                start = time.perf_counter()
                integrator.step(20)
                per_step = (time.perf_counter() - start) / 20
                steps[method] = max(1, int(batch_seconds / max(per_step, 1e-9)))
            per_step = common.interleaved_median(runs, steps, batches)
            for method in runs:
                rows.append({"system": label, "platform": platform_name, "method": method,
                             "us_per_step": per_step[method] * 1e6})
            ratio = rows[-2]["us_per_step"] / rows[-1]["us_per_step"]
            log("  %-20s %-9s M-RATTLE %.1f us/step, splitting %.1f us/step (ratio %.2f)" % (
                label, platform_name, rows[-2]["us_per_step"], rows[-1]["us_per_step"], ratio))
    return rows
