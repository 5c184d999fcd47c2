"""`./benchmarks/run.sh validate-thermostats`: MRattleNoseHooverIntegrator and MRattleBussiIntegrator on rigid
TIP3P water from one start, beside NVE and LangevinMiddle + SETTLE: canonical kinetic energy, potential energy,
diffusion at 2 fs and the conserved quantity's drift at 0.5-5 fs (the method: report())."""
import math
import time

import numpy as np
from openmm import unit

import mrattle

from .common import (KB, TEMPERATURE, block_mean, context as start_context, equilibrate, masses as masses_of,
                     temperatures, water, water_integrator, write_csv)
from .stats import drift_with_error

METHODS = ('M-RATTLE NVE', 'M-RATTLE Nose-Hoover chain', 'M-RATTLE CSVR', 'LangevinMiddle + SETTLE')
BLOCKS = 10
SAMPLE_FS = 10.0  # between samples of every run


def diffusion(times, oxygens, segments=4):
    """D (1e-5 cm^2/s) from the oxygens' mean-squared displacement: in each of `segments` equal time segments,
    the slope over lags of 20-60 % of it (all time origins), D = slope/6; mean and standard error."""
    t = np.asarray(times) - times[0]
    x = np.asarray(oxygens)  # frames x molecules x 3, unwrapped
    values = []
    for frames in np.array_split(np.arange(len(t)), segments):
        ts, xs = t[frames] - t[frames[0]], x[frames]
        lags = [k for k in range(1, len(ts)) if 0.2 * ts[-1] <= ts[k] <= 0.6 * ts[-1]]
        msd = [np.mean(np.sum((xs[k:] - xs[:-k]) ** 2, axis=2)) for k in lags]
        slope = np.polyfit(ts[lags], msd, 1)[0]  # nm^2/ps
        values.append(slope / 6 * 1e-2 / 1e-5)  # nm^2/ps = 1e-2 cm^2/s
    return np.mean(values), np.std(values, ddof=1) / math.sqrt(segments)


def run_series(method, step_fs, ps, start, system, bodies, threads, sample_fs=SAMPLE_FS, keep_oxygens=False):
    """One run's series (every sample_fs): time, kinetic, potential, conserved energy, T_trans, T_rot; oxygen
    positions."""
    integrator = water_integrator(method, step_fs)
    context = start_context(system, integrator, start[0], start[1], 'CPU', threads)
    rigid = isinstance(integrator, mrattle.RigidBodyIntegrator)
    bath = getattr(integrator, 'computeHeatBathEnergy', None)
    masses = masses_of(system)
    oxygen = [body[0] for body in bodies]
    stride = max(1, int(round(sample_fs / step_fs)))
    series = {key: [] for key in ('time', 'kinetic', 'potential', 'conserved', 'Ttrans', 'Trot')}
    oxygens = []
    began = time.time()
    for _ in range(int(round(ps * 1000 / (stride * step_fs)))):
        integrator.step(stride)
        state = context.getState(getEnergy=True, getVelocities=not rigid, getPositions=keep_oxygens)
        kinetic = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        potential = state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        if rigid:
            split = (integrator.computeTranslationalTemperature().value_in_unit(unit.kelvin),
                     integrator.computeRotationalTemperature().value_in_unit(unit.kelvin))
        else:  # its half-step velocities, as LangevinMiddle reports them
            split = temperatures(state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond),
                                 masses, bodies, True)
        for key, value in (('time', state.getTime().value_in_unit(unit.picosecond)), ('kinetic', kinetic),
                           ('potential', potential), ('Ttrans', split[0]), ('Trot', split[1]),
                           ('conserved', kinetic + potential + (bath().value_in_unit(unit.kilojoule_per_mole) if bath else 0))):
            series[key].append(value)
        if keep_oxygens:
            oxygens.append(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)[oxygen])
        if not math.isfinite(series['conserved'][-1]):
            raise ArithmeticError('%s at %g fs: energy not finite' % (method, step_fs))
    return series, oxygens, time.time() - began


CSV_COLUMNS = ['method', 'step_fs', 'ps', 'kinetic_mean', 'kinetic_mean_se', 'kinetic_variance', 'kinetic_variance_se',
               'potential_per_molecule', 'potential_per_molecule_se', 'Ttrans', 'Ttrans_se', 'Trot', 'Trot_se',
               'D_1e-5_cm2_per_s', 'D_se', 'drift_kJ_per_mol_ns_per_molecule', 'drift_se', 'failure', 'wall_s']
STEPS_FS = (2, 0.5, 1, 3, 4, 5)


def run(quick, out, log, threads=1):
    """Every run (a row each in out + '.csv', rewritten as each run ends); returns the report as markdown lines."""
    production_ps, short_ps, equilibrate_ps = (0.2, 0.1, 0.05) if quick else (20.0, 2.0, 2.0)
    system, positions, bodies = water()
    start = equilibrate(system, positions, equilibrate_ps, threads)
    rows = []
    for method, step_fs in [(m, h) for m in METHODS for h in STEPS_FS if h == 2 or m != METHODS[3]]:
        ps = production_ps if step_fs == 2 else short_ps
        rows.append(run_one(method, step_fs, ps, start, system, bodies, threads))
        log('thermostats: %s' % rows[-1])
        write_csv(out + '.csv', rows, CSV_COLUMNS)
    return report(rows, len(bodies), quick, production_ps, short_ps, equilibrate_ps, threads)


def run_one(method, step_fs, ps, start, system, bodies, threads):
    """One run's row: in production (at 2 fs) the sampling figures, at every step the temperatures and drift."""
    production = step_fs == 2
    try:
        series, oxygens, wall = run_series(method, step_fs, ps, start, system, bodies, threads, keep_oxygens=production)
    except Exception as error:  # a blow-up is a result
        return dict(method=method, step_fs=step_fs, ps=ps, failure=str(error).splitlines()[0])
    row, n = dict(method=method, step_fs=step_fs, ps=ps, wall_s=round(wall)), len(bodies)
    if method != 'LangevinMiddle + SETTLE':  # it conserves nothing
        drift, drift_se = drift_with_error(series['time'], series['conserved'])
        row['drift_kJ_per_mol_ns_per_molecule'], row['drift_se'] = drift / n, drift_se / n
    for key in ('Ttrans', 'Trot'):
        row[key], row[key + '_se'] = block_mean(series[key], BLOCKS)
    if production:
        row['kinetic_mean'], row['kinetic_mean_se'] = block_mean(series['kinetic'], BLOCKS)
        # The variance: the squared deviations from the whole run's mean, block-averaged.
        kinetic = np.asarray(series['kinetic'], float)
        row['kinetic_variance'], row['kinetic_variance_se'] = block_mean((kinetic - kinetic.mean()) ** 2, BLOCKS)
        u, u_se = block_mean(series['potential'], BLOCKS)
        row['potential_per_molecule'], row['potential_per_molecule_se'] = u / n, u_se / n
        row['D_1e-5_cm2_per_s'], row['D_se'] = diffusion(series['time'], oxygens)
    return row


def report(rows, molecules, quick, production_ps, short_ps, equilibrate_ps, threads):
    """The section, from the runs' rows."""
    dof = 6 * molecules - 3
    kT = KB * TEMPERATURE
    mean_k, variance_k = 0.5 * dof * kT, 0.5 * dof * kT * kT

    def pm(row, key, se, digits=1):
        return ('%.*f +- %.*f' % (digits, row[key], digits, row[se])) if key in row else '-'

    def sigmas(row, key, se, target):
        return '%+.1f' % ((row[key] - target) / row[se]) if key in row and row[se] > 0 else '-'

    md = ['\n## Thermostats for rigid water: Nose-Hoover chain and CSVR (issue 33)\n',
          '%d waters, CPU platform with %d thread(s), one start (%g ps of LangevinMiddle + SETTLE); %g ps at 2 fs, %g ps '
          'at the other steps; %d blocks. N = %d degrees of freedom: canonical <K> = N kT/2 = %.1f kJ/mol, '
          'var K = N (kT)^2/2 = %.0f (kJ/mol)^2. The method: `docs/benchmarks.md`, "Thermostats".%s\n'
          % (molecules, threads, equilibrate_ps, production_ps, short_ps, BLOCKS, dof, mean_k, variance_k,
             ' **Quick smoke run: too short to conclude anything.**' if quick else '')]
    md.append('### Canonical sampling at 2 fs\n')
    md.append('| Method | <K> (kJ/mol) | (<K> - canonical)/SE | var K ((kJ/mol)^2) | (var - canonical)/SE | '
              'U per water (kJ/mol) | D (1e-5 cm^2/s) | T_trans (K) | T_rot (K) |')
    md.append('|---|---|---|---|---|---|---|---|---|')
    for row in rows:
        if row['step_fs'] != 2:
            continue
        if row.get('failure'):
            md.append('| %s | failed: %s | | | | | | | |' % (row['method'], row['failure']))
            continue
        md.append('| %s | %s | %s | %s | %s | %s | %s | %s | %s |' % (
            row['method'], pm(row, 'kinetic_mean', 'kinetic_mean_se'),
            sigmas(row, 'kinetic_mean', 'kinetic_mean_se', mean_k), pm(row, 'kinetic_variance', 'kinetic_variance_se', 0),
            sigmas(row, 'kinetic_variance', 'kinetic_variance_se', variance_k),
            pm(row, 'potential_per_molecule', 'potential_per_molecule_se', 3), pm(row, 'D_1e-5_cm2_per_s', 'D_se', 2),
            pm(row, 'Ttrans', 'Ttrans_se'), pm(row, 'Trot', 'Trot_se')))
    md.append('\n### Conserved quantity against the step size\n')
    md.append('| Method | Step (fs) | Run (ps) | Drift (kJ/mol/ns per water) |')
    md.append('|---|---|---|---|')
    for row in sorted(rows, key=lambda r: (METHODS.index(r['method']) if r['method'] in METHODS else 99, r['step_fs'])):
        if row.get('failure'):
            md.append('| %s | %g | %g | failed: %s |' % (row['method'], row['step_fs'], row['ps'], row['failure']))
            continue
        if 'drift_se' in row:  # LangevinMiddle conserves nothing
            md.append('| %s | %g | %g | %s |' % (row['method'], row['step_fs'], row['ps'],
                                                pm(row, 'drift_kJ_per_mol_ns_per_molecule', 'drift_se', 3)))
    return md
