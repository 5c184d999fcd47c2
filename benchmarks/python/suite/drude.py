"""Validation of the Drude integrators against OpenMM's with SETTLE on SWM4-NDP water (`./benchmarks/run.sh
validate-drude`): MRattleDrudeLangevinIntegrator against DrudeLangevinIntegrator, MRattleDrudeNoseHooverIntegrator
against DrudeNoseHooverIntegrator, same settings, same System. Writes its table to <out>/drude.md."""
import datetime
import math
import os
import subprocess

import numpy as np
import openmm
from openmm import unit

import mrattle
from .common import KB, TEMPERATURE, context, density, git_commit, interleaved, machine_description, masses as masses_of, removes_cm

STEP, DRUDE_T, WALL = 0.001, 1.0, 0.02  # ps, K, nm: OpenMM's tests' settings and its default hard wall
COUPLING = {'Langevin': (1.0, 10.0), 'Nose-Hoover': (1.0, 10.0)}  # 1/ps: the bodies', the Drude particles'
# steps (1 fs): common NVT and NPT equilibration, each replica's own equilibration and production, sample stride
# and the Drude T at shorter steps, where the schemes' differences shrink as h^2
FULL = dict(box=1.9, step=STEP, equilibrate=15000, settle=2000, nvt=8000, npt=8000, sample=20, replicas=4, batches=7,
            finer=[dict(step=STEP / 2, settle=1000, nvt=6000, sample=40, replicas=3),
                   dict(step=STEP / 4, settle=1200, nvt=4800, sample=40, replicas=3)])
# The Langevin Drude T against the bodies' friction (1/ps; Drude 10/ps), at 0.5 fs: its own table, drude-friction.md
FRICTION = dict(frictions=(0.2, 1.0, 5.0), equilibrate=6000, step=STEP / 2, settle=1000, nvt=3000, sample=20, replicas=3)
QUICK_FRICTION = dict(frictions=(0.2, 5.0), equilibrate=200, step=STEP / 2, settle=100, nvt=100, sample=20, replicas=2)
QUICK = dict(box=1.9, step=STEP, equilibrate=500, settle=200, nvt=200, npt=200, sample=20, replicas=2, batches=2,
             finer=[dict(step=STEP / 2, settle=200, nvt=200, sample=40, replicas=2),
                    dict(step=STEP / 4, settle=200, nvt=200, sample=40, replicas=2)])


def swm4ndp(box_nm):
    """A cubic SWM4-NDP box (mrattle.models.swm4ndpWater: PME 0.8 nm, SETTLE), its Drude pairs and bodies (O, H1, H2)."""
    model = mrattle.models.swm4ndpWater(boxSize=box_nm * unit.nanometer)
    system = model.system
    drude = next(f for f in system.getForces() if isinstance(f, openmm.DrudeForce))
    pairs = np.array([drude.getParticleParameters(i)[1::-1] for i in range(drude.getNumParticles())])  # (core, Drude)
    return system, model.positions, pairs, mrattle.rigidBodies(model.topology, system, atoms=['O', 'H1', 'H2'])


def integrator(name, bodies, seed, step=STEP, coupling=None):
    """The four integrators by name: (thermostat, plugin or not); coupling: (the bodies', the Drude particles') if not COUPLING's."""
    thermostat, plugin = name
    cls = getattr(mrattle if plugin else openmm, 'MRattle' * plugin + 'Drude%sIntegrator' % thermostat.replace('-', ''))
    gamma, drude_gamma = coupling or COUPLING[thermostat]
    result = cls(TEMPERATURE, gamma, DRUDE_T, drude_gamma, step)
    result.setMaxDrudeDistance(WALL)
    if thermostat == 'Langevin':
        result.setRandomNumberSeed(seed)
    for body in bodies if plugin else []:
        result.addRigidBody(body)
    return result


class Temperatures:
    """Body and Drude temperature from velocities as OpenMM's Drude integrators compute them
    (computeTemperaturesFromVelocities in 8.x, written once for both sides): each pair's relative motion, with
    its reduced mass, is the Drude part; the rest is the body part, over 3 per massive particle - 3 per Drude
    particle - 1 per constraint - 3 with a CMMotionRemover (6 per water, -3: the plugin's count too)."""

    def __init__(self, system, pairs):
        self.m, self.pairs = masses_of(system), pairs
        self.reduced = 1 / (1 / self.m[pairs[:, 0]] + 1 / self.m[pairs[:, 1]])
        self.dof = 3 * (np.count_nonzero(self.m) - len(pairs)) - system.getNumConstraints() - 3 * removes_cm(system)
        scratch = openmm.XmlSerializer.clone(system)  # OpenMM's velocity constraints (SETTLE) and thermal velocities
        for i in reversed(range(scratch.getNumForces())):
            if not isinstance(scratch.getForce(i), openmm.DrudeForce):
                scratch.removeForce(i)
        self.scratch = openmm.Context(scratch, integrator(('Langevin', False), [], 1),
                                      openmm.Platform.getPlatformByName('Reference'))

    def thermal(self, positions, seed):  # as OpenMM's Drude integrators draw them: the pairs' relative motion at 1 K
        self.scratch.setPositions(positions)
        self.scratch.setVelocitiesToTemperature(TEMPERATURE, seed)
        return self.scratch.getState(getVelocities=True).getVelocities()

    def __call__(self, state, shift=0.0):
        """(body T, Drude T); shift: the step h, the velocities moved by h/2 and constrained."""
        v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
        if shift:
            f = state.getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole / unit.nanometer)
            massive = self.m > 0
            v[massive] += 0.5 * shift * f[massive] / self.m[massive, None]
            self.scratch.setPositions(state.getPositions())
            self.scratch.setVelocities(v)
            self.scratch.applyVelocityConstraints(1e-10)
            v = self.scratch.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(
                unit.nanometer / unit.picosecond)
        relative = 0.5 * np.sum(self.reduced * np.sum((v[self.pairs[:, 0]] - v[self.pairs[:, 1]]) ** 2, axis=1))
        total = 0.5 * np.sum(self.m * np.sum(v * v, axis=1))
        return 2 * (total - relative) / (self.dof * KB), 2 * relative / (3 * len(self.pairs) * KB)


def seed_barostat(system, seed):
    """The System's MonteCarloBarostat (if any) drawn from seed in the next Context: reproducible NPT runs."""
    for force in system.getForces():
        if isinstance(force, openmm.MonteCarloBarostat):
            force.setRandomNumberSeed(seed)


def replica(name, model, start, seed, s, npt):
    """One replica's means: from the common start, new velocities (seed; drawn OpenMM's way for both sides: the
    plugin's setVelocitiesToTemperature gives the Drude particles the main temperature), its own equilibration."""
    system, pairs, bodies, temperatures = model
    it = integrator(name, bodies, seed, s['step'], s.get('coupling'))
    seed_barostat(system, seed)
    c = context(system, it, start[0], None, 'CPU', 1)
    c.setPeriodicBoxVectors(*start[1])
    c.setVelocities(temperatures.thermal(start[0], seed))
    it.step(s['settle'])
    rows = []
    for _ in range(s['npt' if npt else 'nvt'] // s['sample']):
        it.step(s['sample'])
        state = c.getState(getEnergy=True, getVelocities=not npt, getPositions=not npt, getForces=not npt)
        row = dict(U=state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole) / len(bodies),
                   density=density(state, temperatures.m))
        if not npt:  # the velocities as they are (OpenMM 8's computeDrudeTemperature()) and, for DrudeLangevin,
            row['T_body'], row['T_drude'] = temperatures(state)  # shifted by h/2 as its getKineticEnergy() (7.7, 8)
            if name == ('Langevin', False):
                row['shifted_T_body'], row['shifted_T_drude'] = temperatures(state, shift=s['step'])
            if name[1]:
                row['own_T_body'] = it.computeBodyTemperature().value_in_unit(unit.kelvin)
                row['own_T_drude'] = it.computeDrudeTemperature().value_in_unit(unit.kelvin)
        rows.append(row)
    return {key: np.mean([r[key] for r in rows]) for key in rows[0]}


def equilibrate(system, positions, steps, seed=1, coupling=None):
    """OpenMM's DrudeLangevin + SETTLE from positions (minimized first): the common start (positions, box)."""
    it = integrator(('Langevin', False), [], seed, coupling=coupling)
    seed_barostat(system, seed)
    c = context(system, it, positions, None, 'CPU', 1)
    openmm.LocalEnergyMinimizer.minimize(c, 10.0, 500)
    c.setVelocitiesToTemperature(TEMPERATURE * unit.kelvin, seed)
    it.step(steps)
    state = c.getState(getPositions=True)
    return state.getPositions(), state.getPeriodicBoxVectors()


QUICK_NOTE = ' A **quick** smoke run: it shows nothing.'


def run_stamp(quick):
    """A table's run: the command's --quick, the time (UTC), the commit and the machine."""
    return (' --quick' if quick else '', datetime.datetime.utcnow().strftime('%Y-%m-%d %H:%M'), git_commit(),
            machine_description())


def mean_se(replicas, key):
    return np.mean([r[key] for r in replicas]), np.std([r[key] for r in replicas], ddof=1) / math.sqrt(len(replicas))


def finer_row(thermostat, f, ours, theirs):
    """The Drude T at a shorter step; for DrudeLangevin also its velocities shifted by h/2 (the difference is to those)."""
    (a, ea), (b, eb) = mean_se(ours, 'T_drude'), mean_se(theirs, 'T_drude')
    if thermostat == 'Langevin':
        shifted, es = mean_se(theirs, 'shifted_T_drude')
        theirs_text, difference = '%.3f +- %.3f, shifted by h/2 %.3f +- %.3f' % (b, eb, shifted, es), (a - shifted) / math.hypot(ea, es)
    else:
        theirs_text, difference = '%.3f +- %.3f' % (b, eb), (a - b) / math.hypot(ea, eb)
    return '| Drude T at %g fs, %d replicas of %g ps (K) | %.3f +- %.3f | %s | %+.1f |' % (
        f['step'] * 1e3, f['replicas'], f['nvt'] * f['step'], a, ea, theirs_text, difference)


def run(quick, out, log):
    s = QUICK if quick else FULL
    system, positions, pairs, bodies = swm4ndp(s['box'])
    model = (system, pairs, bodies, Temperatures(system, pairs))
    names = [(t, p) for t in COUPLING for p in (True, False)]
    log('drude: %d SWM4-NDP waters, common NVT equilibration' % len(bodies))
    nvt_start = equilibrate(system, positions, s['equilibrate'])
    contexts = {n: context(system, integrator(n, bodies, 1), nvt_start[0], model[3].thermal(nvt_start[0], 1), 'CPU', 1)
                for n in names}  # the cost first, while nothing else of this run is running
    per_step = {n: float(np.median(t)) for n, t in interleaved(
        {n: c.getIntegrator() for n, c in contexts.items()}, dict.fromkeys(names, 100), s['batches']).items()}
    del contexts
    means = {n: [replica(n, model, nvt_start, 11 + r, s, False) for r in range(s['replicas'])] for n in names}
    finer = [{n: [replica(n, model, nvt_start, 31 + r, f, False) for r in range(f['replicas'])] for n in names}
             for f in s['finer']]
    log('drude: NVT replicas done')
    system.addForce(openmm.MonteCarloBarostat(1 * unit.bar, TEMPERATURE * unit.kelvin, 25))
    npt_start = equilibrate(system, nvt_start[0], s['equilibrate'], seed=2)
    for n in names:
        npt = [replica(n, model, npt_start, 21 + r, s, True) for r in range(s['replicas'])]
        means[n] = [dict(m, density=p['density']) for m, p in zip(means[n], npt)]
    log('drude: NPT replicas done')
    lines = ['# Drude integrators against OpenMM\'s with SETTLE: SWM4-NDP water\n',
             '`./benchmarks/run.sh validate-drude%s`, %s UTC, commit %s, %s. %d waters (OpenMM\'s swm4ndp.xml, '
             'Modeller.addExtraParticles, PME 0.8 nm), 1 fs, 300 K, Drude 1 K, maxDrudeDistance %g nm, CPU platform, '
             '1 thread. Each integrator: %d replicas (seeds and starting velocities) from one start after %g ps of '
             'OpenMM\'s DrudeLangevin; each %g ps of its own equilibration, then %g ps NVT (sampled every %d fs), and '
             'the same from an NPT start (MonteCarloBarostat, 1 bar, every 25 steps, seeded as the replica) for %g ps '
             'NPT. Means +- standard '
             'errors over the replicas. Temperatures: one formula (OpenMM 8\'s computeSystemTemperature() and '
             'computeDrudeTemperature()) for both sides, from the velocities the integrators keep. Cost: median of %d '
             'interleaved batches '
             'of 100 steps.%s\n' % (
                 *run_stamp(quick), len(bodies), WALL, s['replicas'], s['equilibrate'] * STEP, s['settle'] * STEP,
                 s['nvt'] * STEP, s['sample'], s['npt'] * STEP, s['batches'], QUICK_NOTE if quick else '')]
    for thermostat, (gamma, drude_gamma) in COUPLING.items():
        ours, theirs = means[(thermostat, True)], means[(thermostat, False)]
        lines += ['\n## %s (%g/ps, Drude %g/ps): MRattleDrude%sIntegrator against Drude%sIntegrator + SETTLE\n' % (
            thermostat, gamma, drude_gamma, *[thermostat.replace('-', '')] * 2),
            '| quantity | M-RATTLE | OpenMM + SETTLE | difference / combined SE |', '|---|---|---|---|']
        for key, title, digits in (('U', 'potential energy per molecule (kJ/mol)', 3), ('T_body', 'body T (K)', 2),
                                   ('T_drude', 'Drude T (K)', 3), ('density', 'density, NPT 1 bar (g/mL)', 4)):
            (a, ea), (b, eb) = mean_se(ours, key), mean_se(theirs, key)
            lines.append('| %s | %.*f +- %.*f | %.*f +- %.*f | %+.1f |' % (
                title, digits, a, digits, ea, digits, b, digits, eb, (a - b) / math.hypot(ea, eb)))
        for f, runs in zip(s['finer'], finer):
            lines.append(finer_row(thermostat, f, runs[(thermostat, True)], runs[(thermostat, False)]))
        lines.append('| the plugin\'s own computeBodyTemperature(), computeDrudeTemperature() (K) | %.2f +- %.2f, '
                     '%.3f +- %.3f | | |' % (*mean_se(ours, 'own_T_body'), *mean_se(ours, 'own_T_drude')))
        if thermostat == 'Langevin':
            lines.append('| DrudeLangevin\'s velocities shifted by h/2, as its getKineticEnergy(): body, Drude T '
                         '(K) | | %.2f +- %.2f, %.3f +- %.3f | |' % (*mean_se(theirs, 'shifted_T_body'),
                                                                 *mean_se(theirs, 'shifted_T_drude')))
        ms = [1e3 * per_step[(thermostat, p)] for p in (True, False)]
        lines.append('| cost per step, CPU, 1 thread, PME included (ms) | %.2f | %.2f | ratio %.2f (target <= 1.2) |'
                     % (ms[0], ms[1], ms[0] / ms[1]))
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, 'drude.md'), 'w') as f:
        f.write('\n'.join(lines) + '\n')
    log('drude: wrote %s' % os.path.join(out, 'drude.md'))


def friction_scan(quick, out, log):
    """The Langevin pair's Drude temperature at 0.5 fs for several body frictions (Drude friction 10/ps, no
    barostat): a gap that grows with the bodies' friction is the 300 K bath reaching the Drude motion."""
    f = QUICK_FRICTION if quick else FRICTION
    system, positions, pairs, bodies = swm4ndp(FULL['box'])
    model = (system, pairs, bodies, Temperatures(system, pairs))
    lines = ['# The Langevin Drude temperature against the bodies\' friction: SWM4-NDP water\n',
             '`./benchmarks/run.sh validate-drude --only friction%s`, %s UTC, commit %s, %s. %d waters, 0.5 fs, 300 K, '
             'Drude 1 K at 10/ps, maxDrudeDistance %g nm, CPU platform, 1 thread. For each body friction: a start after '
             '%g ps of OpenMM\'s DrudeLangevin at that friction, then per integrator %d replicas of %g ps equilibration '
             'and %g ps NVT (sampled every %g fs). Drude T by OpenMM\'s formula; DrudeLangevin\'s also shifted by h/2 '
             '(the difference is to those). Means +- standard errors over the replicas.%s\n' % (
                 *run_stamp(quick), len(bodies), WALL, f['equilibrate'] * f['step'], f['replicas'],
                 f['settle'] * f['step'], f['nvt'] * f['step'], f['sample'] * f['step'] * 1e3,
                 QUICK_NOTE if quick else ''),
             '| body friction (1/ps) | M-RATTLE Drude T (K) | DrudeLangevin + SETTLE, kept (K) | shifted by h/2 (K) | '
             'difference (K) | difference / combined SE |', '|---|---|---|---|---|---|']
    for gamma in f['frictions']:
        s = dict(f, coupling=(gamma, COUPLING['Langevin'][1]))
        start = equilibrate(system, positions, f['equilibrate'], coupling=s['coupling'])
        ours = [replica(('Langevin', True), model, start, 51 + r, s, False) for r in range(f['replicas'])]
        theirs = [replica(('Langevin', False), model, start, 51 + r, s, False) for r in range(f['replicas'])]
        (a, ea), (b, eb), (c, ec) = (mean_se(ours, 'T_drude'), mean_se(theirs, 'T_drude'),
                                     mean_se(theirs, 'shifted_T_drude'))
        lines.append('| %g | %.3f +- %.3f | %.3f +- %.3f | %.3f +- %.3f | %+.3f | %+.1f |' % (
            gamma, a, ea, b, eb, c, ec, a - c, (a - c) / math.hypot(ea, ec)))
        log('drude friction %g/ps done' % gamma)
    os.makedirs(out, exist_ok=True)
    with open(os.path.join(out, 'drude-friction.md'), 'w') as stream:
        stream.write('\n'.join(lines) + '\n')
    log('drude: wrote %s' % os.path.join(out, 'drude-friction.md'))
