"""`./benchmarks/run.sh validate-thermostats`: MRattleNoseHooverIntegrator and MRattleBussiIntegrator on rigid
TIP3P water from one start, beside NVE and LangevinMiddle + SETTLE: canonical kinetic energy, potential energy,
diffusion at 2 fs and the conserved quantity's drift at 0.5-5 fs (the method: report()). Follow-up studies
(--study): the potential energy at smaller steps (is the 2-fs difference a step-size error?) and the density
under a barostat, reported in the same section when their CSVs lie beside the main one."""
import os
import math
import time

import numpy as np
from openmm import unit

import mrattle

from .common import (KB, TEMPERATURE, block_mean, context as start_context, density, equilibrate, masses as masses_of,
                     read_csv, temperatures, water, water_integrator, write_csv)
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
    """One run's series (every sample_fs): time, kinetic, potential, conserved energy, T_trans, T_rot, density;
    oxygen positions."""
    integrator = water_integrator(method, step_fs)
    context = start_context(system, integrator, start[0], start[1], 'CPU', threads)
    rigid = isinstance(integrator, mrattle.RigidBodyIntegrator)
    bath = getattr(integrator, 'computeHeatBathEnergy', None)
    masses = masses_of(system)
    oxygen = [body[0] for body in bodies]
    stride = max(1, int(round(sample_fs / step_fs)))
    series = {key: [] for key in ('time', 'kinetic', 'potential', 'conserved', 'Ttrans', 'Trot', 'density')}
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
                           ('conserved', kinetic + potential + (bath().value_in_unit(unit.kilojoule_per_mole) if bath else 0)),
                           ('density', density(state, masses))):
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


def runs(name, out, columns, plan, make_row, log):
    """A row per (method, step) of the plan, from make_row; out + '.csv' rewritten as each run ends."""
    rows = []
    for method, step_fs in plan:
        rows.append(make_row(method, step_fs))
        log('%s: %s' % (name, rows[-1]))
        write_csv(out + '.csv', rows, columns)
    return rows


def run(quick, out, log, threads=1):
    """Every run (a row each in out + '.csv'); returns the report as markdown lines."""
    production_ps, short_ps, equilibrate_ps = (0.2, 0.1, 0.05) if quick else (20.0, 2.0, 2.0)
    system, positions, bodies = water()
    start = equilibrate(system, positions, equilibrate_ps, threads)
    rows = runs('thermostats', out, CSV_COLUMNS, [(m, h) for m in METHODS for h in STEPS_FS if h == 2 or m != METHODS[3]],
                lambda m, h: run_one(m, h, production_ps if h == 2 else short_ps, start, system, bodies, threads), log)
    return report(rows, len(bodies), quick, production_ps, short_ps, equilibrate_ps, threads)


STEP_SIZE_METHODS = METHODS[1:]  # the sampling ones
# MRattleLangevinIntegrator (1/ps): LangevinMiddle's splitting with M-RATTLE, to tell the splitting's share of a
# difference from M-RATTLE's.
M_RATTLE_LANGEVIN = 'M-RATTLE Langevin'
# (method, step in fs) of the study; the others' 2 fs rows are the main run's production rows. LangevinMiddle
# runs from 1 fs only: its configurational sampling is the reference.
STEP_SIZE_RUNS = [(m, h) for h in (1.5, 1, 0.5) for m in STEP_SIZE_METHODS if h >= 1 or m != METHODS[3]] + \
    [(M_RATTLE_LANGEVIN, 2), (M_RATTLE_LANGEVIN, 1)]


def run_step_sizes(quick, out, log, threads=1, ps=20.0):
    """The potential energy's step-size dependence (NVT): STEP_SIZE_RUNS for `ps` each from the main run's start."""
    ps, equilibrate_ps = (0.2, 0.05) if quick else (ps, 2.0)
    system, positions, bodies = water()
    start = equilibrate(system, positions, equilibrate_ps, threads)
    return runs('thermostats step sizes', out, CSV_COLUMNS, STEP_SIZE_RUNS,
                lambda m, h: run_one(m, h, ps, start, system, bodies, threads, production=True), log)


DENSITY_COLUMNS = ['method', 'step_fs', 'ps', 'discarded_ps', 'density', 'density_se', 'potential_per_molecule',
                   'potential_per_molecule_se', 'T', 'T_se', 'failure', 'wall_s']
DENSITY_EQUILIBRATE_PS = 10.0


def run_density(quick, out, log, threads=1, ps=40.0, discard_ps=4.0, equilibrate_ps=DENSITY_EQUILIBRATE_PS):
    """NPT (MonteCarloBarostat, 1 bar, 300 K): each thermostat and LangevinMiddle + SETTLE at 2 fs from one start
    (equilibrate_ps under the barostat), discard_ps dropped, then ps sampled: density, U per water and T."""
    if quick:
        ps, discard_ps, equilibrate_ps = 0.2, 0.02, 0.05
    system, positions, bodies = water(barostat_seed=7)
    start = equilibrate(system, positions, equilibrate_ps, threads)
    dof = 6 * len(bodies) - 3

    def row(method, step_fs):
        row = dict(method=method, step_fs=step_fs, ps=ps, discarded_ps=discard_ps)
        try:
            series, _, wall = run_series(method, step_fs, discard_ps + ps, start, system, bodies, threads)
        except Exception as error:  # a blow-up is a result
            return dict(row, failure=str(error).splitlines()[0])
        kept = len(series['time']) - int(round(ps * 1000 / SAMPLE_FS))
        row['density'], row['density_se'] = block_mean(series['density'][kept:], BLOCKS)
        u, u_se = block_mean(series['potential'][kept:], BLOCKS)
        row['potential_per_molecule'], row['potential_per_molecule_se'] = u / len(bodies), u_se / len(bodies)
        k, k_se = block_mean(series['kinetic'][kept:], BLOCKS)
        row['T'], row['T_se'] = 2 * k / (dof * KB), 2 * k_se / (dof * KB)
        return dict(row, wall_s=round(wall))
    return runs('thermostats NPT', out, DENSITY_COLUMNS, [(m, 2) for m in STEP_SIZE_METHODS], row, log)


def run_one(method, step_fs, ps, start, system, bodies, threads, production=None):
    """One run's row: in production (by default at 2 fs) the sampling figures, at every step the temperatures
    and drift."""
    production = step_fs == 2 if production is None else production
    try:
        series, oxygens, wall = run_series(method, step_fs, ps, start, system, bodies, threads, keep_oxygens=production)
    except Exception as error:  # a blow-up is a result
        return dict(method=method, step_fs=step_fs, ps=ps, failure=str(error).splitlines()[0])
    row, n = dict(method=method, step_fs=step_fs, ps=ps, wall_s=round(wall)), len(bodies)
    if method not in ('LangevinMiddle + SETTLE', M_RATTLE_LANGEVIN):  # they conserve nothing
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


def report(rows, molecules, quick, production_ps, short_ps, equilibrate_ps, threads, step_rows=None, density_rows=None):
    """The section: the main run's rows, and the follow-up studies' (step sizes, density) where given."""
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
    if step_rows:
        md += report_step_sizes([r for r in rows if r['step_fs'] == 2 and r['method'] in STEP_SIZE_METHODS] + step_rows,
                                dof, kT)
    if density_rows:
        md += report_density(density_rows)
    return md


def combined(a, b, key, se):
    """a - b, its standard error (the two added in quadrature) and the difference in those errors."""
    difference, error = a[key] - b[key], math.hypot(a[se], b[se])
    return difference, error, difference / error


def report_step_sizes(rows, dof, kT):
    """The potential energy per water against the step size (NVT), beside LangevinMiddle + SETTLE's pooled over
    its steps (its configurational sampling is accurate at any step: its own fit below checks that)."""
    reference = pooled([r for r in rows if r['method'] == 'LangevinMiddle + SETTLE' and 'potential_per_molecule' in r])
    md = ['\n### Potential energy against the step size (NVT)\n',
          'The reference, LangevinMiddle + SETTLE\'s U per water pooled over its steps: %.3f +- %.3f kJ/mol.\n' % reference,
          '| Method | Step (fs) | Run (ps) | T (K) | U per water (kJ/mol) | U - reference (kJ/mol) |', '|---|---|---|---|---|---|']
    order = {m: k for k, m in enumerate(STEP_SIZE_METHODS + (M_RATTLE_LANGEVIN,))}
    for r in sorted(rows, key=lambda r: (order[r['method']], -r['step_fs'])):
        if r.get('failure'):
            md.append('| %s | %g | %g | failed: %s | | |' % (r['method'], r['step_fs'], r['ps'], r['failure']))
            continue
        d, e = r['potential_per_molecule'] - reference[0], math.hypot(r['potential_per_molecule_se'], reference[1])
        md.append('| %s | %g | %g | %.1f +- %.1f | %.3f +- %.3f | %+.3f +- %.3f (%+.1f) |' % (
            r['method'], r['step_fs'], r['ps'], 2 * r['kinetic_mean'] / (dof * KB),
            2 * r['kinetic_mean_se'] / (dof * KB), r['potential_per_molecule'], r['potential_per_molecule_se'],
            d, e, d / e))
    gaps = []
    for step in sorted({r['step_fs'] for r in rows}, reverse=True):
        both = [r for r in rows if r['step_fs'] == step and r['method'] in STEP_SIZE_METHODS[:2]
                and 'potential_per_molecule' in r]
        if both:
            u, se = pooled(both)
            d, e = u - reference[0], math.hypot(se, reference[1])
            gaps.append('%g fs %+.3f +- %.3f (%+.1f SE%s)' % (step, d, e, d / e, '' if len(both) == 2 else ', one'))
    md.append('\nThe two thermostats pooled at each step, minus the reference: ' + '; '.join(gaps) + '.')
    fits = []
    for method in sorted({r['method'] for r in rows}, key=order.get):
        points = [r for r in rows if r['method'] == method and 'potential_per_molecule' in r]
        if len({r['step_fs'] for r in points}) >= 2:
            (u0, u0_se), (c, c_se), chi2, dof_fit = fit_step_squared(points)
            fits.append('%s: U(0) = %.3f +- %.3f, c = %+.4f +- %.4f kJ/mol/fs^2 (%+.1f SE; chi^2 %.1f for %d)' % (
                method, u0, u0_se, c, c_se, c / c_se, chi2, dof_fit))
    if fits:
        md.append('\nWeighted least-squares fits U per water = U(0) + c h^2 (h in fs): ' + '; '.join(fits) + '.')
    return md


def pooled(points):
    """The inverse-variance weighted mean of the rows' U per water and its standard error."""
    w = 1 / np.array([r['potential_per_molecule_se'] for r in points]) ** 2
    u = np.array([r['potential_per_molecule'] for r in points])
    return float(np.sum(w * u) / np.sum(w)), float(1 / math.sqrt(np.sum(w)))


def fit_step_squared(points):
    """U = U0 + c h^2 by weighted least squares: (U0, SE), (c, SE), chi^2 and its degrees of freedom."""
    h2 = np.array([r['step_fs'] ** 2 for r in points])
    u = np.array([r['potential_per_molecule'] for r in points])
    w = 1 / np.array([r['potential_per_molecule_se'] for r in points]) ** 2
    design = np.column_stack([np.ones_like(h2), h2])
    covariance = np.linalg.inv(design.T @ (w[:, None] * design))
    coefficients = covariance @ design.T @ (w * u)
    chi2 = float(np.sum(w * (u - design @ coefficients) ** 2))
    errors = np.sqrt(np.diag(covariance))
    return (coefficients[0], errors[0]), (coefficients[1], errors[1]), chi2, len(points) - 2


def report_density(rows):
    """NPT: density and potential energy per water beside LangevinMiddle + SETTLE's."""
    reference = [r for r in rows if r['method'] == 'LangevinMiddle + SETTLE' and 'density' in r]
    first = rows[0]
    md = ['\n### Density under a barostat (NPT, 2 fs)\n',
          'One start (%g ps under the barostat); %g ps dropped, %g ps sampled; %d blocks.\n' % (
              DENSITY_EQUILIBRATE_PS, first['discarded_ps'], first['ps'], BLOCKS),
          '| Method | Density (g/mL) | - LangevinMiddle + SETTLE\'s (g/mL) | U per water (kJ/mol) | T (K) |',
          '|---|---|---|---|---|']
    for r in rows:
        if r.get('failure'):
            md.append('| %s | failed: %s | | | |' % (r['method'], r['failure']))
            continue
        if reference and r is not reference[0]:
            d, e, z = combined(r, reference[0], 'density', 'density_se')
            versus = '%+.4f +- %.4f (%+.1f)' % (d, e, z)
        else:
            versus = '(reference)' if reference else '-'
        md.append('| %s | %.4f +- %.4f | %s | %.3f +- %.3f | %.1f +- %.1f |' % (
            r['method'], r['density'], r['density_se'], versus, r['potential_per_molecule'],
            r['potential_per_molecule_se'], r['T'], r['T_se']))
    return md


def validate(args, quick, out, log):
    """`./benchmarks/run.sh validate-thermostats`: the main runs (or, --report-from, their CSV reported), or one
    follow-up study (--study: its CSV, out + '_<study>.csv', which the main report reads beside its own)."""
    if args.study:
        (run_step_sizes if args.study == 'step-sizes' else run_density)(
            quick, out + '_' + args.study.replace('-', '_'), log, args.threads)
        return []
    if args.report_from:
        stem = args.report_from[:-len('.csv')]
        beside = [read_csv(stem + suffix) if os.path.exists(stem + suffix) else None
                  for suffix in ('_step_sizes.csv', '_density.csv')]
        return report(read_csv(args.report_from), 895, False, 20.0, 2.0, 2.0, 1, *beside)
    return run(quick, out, log, args.threads)
