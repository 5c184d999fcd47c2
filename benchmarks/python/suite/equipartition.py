"""`./benchmarks/run.sh validate-equipartition`: translational against rotational temperature of rigid water
against the step size (the method: docs/benchmarks.md, "Equipartition")."""
import math
import multiprocessing
import sys
import time

import numpy as np
from openmm import unit

from .common import (block_mean, context as start_context, equilibrate, masses as masses_of, removes_cm,
                     temperatures, water, water_integrator, write_csv)

MODELS = (('TIP3P', 'tip3p.pdb', 'amber14/tip3p.xml'), ('SPC/E', 'spce.pdb', 'amber14/spce.xml'))
NVE_STEPS_FS = (0.5, 1, 2, 3, 4)
LANGEVIN_STEPS_FS = (2, 4)
METHODS = ('M-RATTLE', 'Verlet + SETTLE')
THERMOSTATS = ('M-RATTLE Nose-Hoover chain', 'M-RATTLE CSVR')  # thermostats.METHODS' names
THERMOSTAT_STEPS_FS = (0.5, 1, 2, 3, 4, 5)
THERMOSTAT_MODELS = ('TIP3P',)  # issue 33's validation system
BLOCKS = 10


def against_published(result):
    """How a run compares with Asthagiri & Beck (2024): equipartition at 0.5 fs, T_rot < T_trans at 1-3 fs."""
    step = result['step_fs']
    if result.get('failure') or step > 3:
        return ''
    d, e = result['Trot_minus_Ttrans'], result['difference_se']
    below, equal = d < -3 * e, abs(d) <= 3 * e
    if step == 0.5:
        return ' (consistent with it)' if equal else ' (differs from it)'
    return ' (consistent with it)' if below else ' (not resolved at this run length)' if equal else ' (contradicts it)'


HALF_STEP = 'Verlet + SETTLE, State velocities (half step)'
# ps equilibrated, ps dropped, ps sampled, fs between samples: sized for a shared 2-core machine
# (a PME step of the 2685-atom box took 0.016-0.17 s there).
LENGTHS = (2.0, 0.3, 2.5, 10)


def summarize(model, method, step_fs, trans, rot, times, energy, failure, wall, steps, molecules):
    """A run's row: T_trans, T_rot and their difference (block-averaged as one series: the two are
    anticorrelated in NVE) with standard errors, and the energy's drift (kJ/mol per ns per molecule)."""
    result = dict(model=model, method=method, step_fs=step_fs, failure=failure or '', wall_s=round(wall), steps=steps)
    if failure is None:
        result['Ttrans'], result['Ttrans_se'] = block_mean(trans, BLOCKS)
        result['Trot'], result['Trot_se'] = block_mean(rot, BLOCKS)
        result['Trot_minus_Ttrans'], result['difference_se'] = block_mean(np.asarray(rot) - np.asarray(trans), BLOCKS)
        result['drift_kJ_per_mol_ns_molecule'] = (np.polyfit(times, energy, 1)[0] if len(times) > 1
                                                  else float('nan')) * 1000 / molecules
    return result


def run_one(model, system, bodies, start, method, step_fs, discard_ps, production_ps, sample_fs, threads):
    """One run's rows (summarize); VerletIntegrator's on-step velocities are its leapfrog State velocities plus
    (h/2) f/m, made rigid, and a second row gives the State velocities as they are."""
    integrator = water_integrator(method, step_fs)
    context = start_context(system, integrator, start[0], start[1], 'CPU', threads)
    masses, cm = masses_of(system), removes_cm(system)
    leapfrog = method == 'Verlet + SETTLE'
    bath = getattr(integrator, 'computeHeatBathEnergy', lambda: 0 * unit.kilojoule_per_mole)
    stride = max(1, int(round(sample_fs / step_fs)))
    samples = int(round(production_ps * 1000 / (stride * step_fs)))
    h = step_fs * 0.001
    began = time.time()
    failure = None
    series = {key: [] for key in ('trans', 'rot', 'halfTrans', 'halfRot', 'time', 'energy')}
    try:
        integrator.step(int(round(discard_ps * 1000 / step_fs)))
        for _ in range(samples):
            integrator.step(stride)
            state = context.getState(getVelocities=True, getPositions=True, getEnergy=True, getForces=leapfrog)
            v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers / unit.picosecond)
            x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometers)
            if leapfrog:
                tt, tr = temperatures(v, masses, bodies, cm)
                series['halfTrans'].append(tt)
                series['halfRot'].append(tr)
                f = state.getForces(asNumpy=True).value_in_unit(unit.kilojoules_per_mole / unit.nanometer)
                v = v + 0.5 * h * f / masses[:, None]
            tt, tr = temperatures(v, masses, bodies, cm, x)
            series['trans'].append(tt)
            series['rot'].append(tr)
            series['time'].append(state.getTime().value_in_unit(unit.picosecond))
            series['energy'].append((state.getKineticEnergy() + state.getPotentialEnergy() + bath()).value_in_unit(
                unit.kilojoule_per_mole))
            if not math.isfinite(series['energy'][-1] + tt + tr):
                raise ArithmeticError('energy not finite at %.2f ps' % series['time'][-1])
    except Exception as error:  # a blow-up ends the run and is reported
        failure = str(error).splitlines()[0]
    wall = time.time() - began
    steps = int(round((discard_ps + production_ps) * 1000 / step_fs))
    results = [summarize(model, method, step_fs, series['trans'], series['rot'], series['time'], series['energy'],
                         failure, wall, steps, len(bodies))]
    if leapfrog:
        results.append(summarize(model, HALF_STEP, step_fs, series['halfTrans'], series['halfRot'], series['time'],
                                 series['energy'], failure, 0.0, steps, len(bodies)))
    return results


def verdict(result):
    """What the error bars support about T_rot - T_trans (3 standard errors)."""
    if result.get('failure'):
        return 'unstable: ' + result['failure']
    d, e = result['Trot_minus_Ttrans'], result['difference_se']
    if abs(d) <= 3 * e:
        return 'equal within 3 SE (%+.1f +- %.1f K)' % (d, e)
    return 'rotational %s translational by %.1f +- %.1f K (%.0f SE)' % ('below' if d < 0 else 'above', abs(d), e,
                                                                        abs(d) / e)


CSV_COLUMNS = ['model', 'method', 'step_fs', 'Ttrans', 'Ttrans_se', 'Trot', 'Trot_se', 'Trot_minus_Ttrans',
               'difference_se', 'drift_kJ_per_mol_ns_molecule', 'failure', 'steps', 'wall_s']


def model_runs(name):
    """(method, step) of every run of a model, the large steps first (cheapest, and where the published bias is)."""
    runs = [(method, step) for step in (3, 4, 2) for method in METHODS]
    runs += [('M-RATTLE Langevin', step) for step in LANGEVIN_STEPS_FS]
    runs += [(method, step) for step in (1, 0.5) for method in METHODS]
    if name in THERMOSTAT_MODELS:
        runs += [(method, step) for method in THERMOSTATS for step in THERMOSTAT_STEPS_FS]
    return runs


def run_model(task):
    """All runs of one model, in a process of its own."""
    name, pdb_name, forcefield_name, lengths, threads = task
    equilibrate_ps, discard_ps, production_ps, sample_fs = lengths
    began = time.time()

    def log(message):
        print('[%6.0f s] equipartition: %s' % (time.time() - began, message), file=sys.stderr, flush=True)

    system, positions, bodies = water(pdb_name, forcefield_name)
    start = equilibrate(system, positions, equilibrate_ps, threads)
    log('%s, %d waters, equilibrated %.1f ps' % (name, len(bodies), equilibrate_ps))
    rows = []
    for method, step in model_runs(name):
        rows += run_one(name, system, bodies, start, method, step, discard_ps, production_ps, sample_fs, threads)
        log('%s %-17s %.1f fs: %s (%d steps in %.0f s)' % (name, method, step, verdict(rows[-1]), rows[-1]['steps'],
                                                            rows[-1]['wall_s']))
    return len(bodies), rows


def run(quick, out, log, threads=1):
    """Every model and step size, the two models in two processes of one CPU thread each (on a shared machine two
    single-thread processes lose less to waiting than one of two threads); writes out + '.csv', returns the report."""
    lengths = (0.02, 0.01, 0.04, 4) if quick else LENGTHS
    began = time.time()
    with multiprocessing.get_context('spawn').Pool(len(MODELS)) as pool:
        results = pool.map(run_model, [(name, pdb, forcefield, lengths, threads) for name, pdb, forcefield in MODELS])
    log('equipartition: both models in %.0f s' % (time.time() - began))
    rows = [row for result in results for row in result[1]]
    write_csv(out + '.csv', rows, CSV_COLUMNS)
    return report(rows, {name: result[0] for (name, _, _), result in zip(MODELS, results)}, quick, *lengths, threads)


def report(rows, by_model, quick, equilibrate_ps, discard_ps, production_ps, sample_fs, threads):
    md = ['\n## Equipartition of rigid water against step size\n',
          'TIP3P (%d waters) and SPC/E (%d waters), CPU platform with %d thread(s) per model; from one start per '
          'model (%s ps of LangevinMiddle + SETTLE), %s ps dropped, then velocities every %s fs for %s ps; %d blocks. '
          'The method: `docs/benchmarks.md`, "Equipartition".%s\n' % (
              by_model.get('TIP3P', 0), by_model.get('SPC/E', 0), threads, equilibrate_ps, discard_ps, sample_fs,
              production_ps, BLOCKS, ' **Quick smoke run: too short to conclude anything.**' if quick else '')]
    md += ['| Model | Step (fs) | Integrator | T_trans (K) | T_rot (K) | T_rot - T_trans (K) | Drift | What the error bars '
           'support |', '|---|---|---|---|---|---|---|---|']
    order = {name: k for k, (name, _, _) in enumerate(MODELS)}
    ranks = {method: k for k, method in enumerate(METHODS + (HALF_STEP, 'M-RATTLE Langevin') + THERMOSTATS)}
    rows = sorted(rows, key=lambda r: (order[r['model']], r['step_fs'], ranks[r['method']]))
    for r in rows:
        if r.get('failure'):
            md.append('| %s | %g | %s | - | - | - | - | %s |' % (r['model'], r['step_fs'], r['method'], verdict(r)))
            continue
        md.append('| %s | %g | %s | %.1f +- %.1f | %.1f +- %.1f | %+.1f +- %.1f | %.3g | %s |' % (
            r['model'], r['step_fs'], r['method'], r['Ttrans'], r['Ttrans_se'], r['Trot'], r['Trot_se'],
            r['Trot_minus_Ttrans'], r['difference_se'], r['drift_kJ_per_mol_ns_molecule'], verdict(r)))
    md.append('\nPer step size, NVE (3 SE as the threshold), against Asthagiri & Beck (2024): equipartition at 0.5 fs, '
              'T_rot < T_trans at 1-3 fs for rigid SPC/E:\n')
    for step in NVE_STEPS_FS:
        parts = ['%s %s: %s%s' % (r['model'], r['method'], verdict(r), against_published(r))
                 for r in rows if r['step_fs'] == step and r['method'] in METHODS]
        published = ('published: equipartition' if step == 0.5 else
                     'published: T_rot below T_trans' if step <= 3 else 'beyond the published range')
        md.append('- **%g fs** (%s): %s.' % (step, published, '; '.join(parts) or 'not run'))
    ok = {(r['model'], r['step_fs'], r['method']): r for r in rows if not r.get('failure')}
    pairs = ['%s %g fs %.1f' % (m, h, abs(r['Trot_minus_Ttrans'] - o['Trot_minus_Ttrans']) /
                                math.hypot(r['difference_se'], o['difference_se']))
             for (m, h, method), r in ok.items() for o in [ok.get((m, h, METHODS[1]))] if method == METHODS[0] and o]
    if pairs:
        md.append('\nM-RATTLE against Verlet + SETTLE (on-step), the same equations from the same start: their '
                  'T_rot - T_trans differ by, in combined standard errors: %s.' % ', '.join(pairs))
    return md

