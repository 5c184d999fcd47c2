"""Validation of MRattleLangevinIntegrator on OpenMM's own inputs, against OpenMM's
LangevinMiddleIntegrator with SETTLE on the same System (`./benchmarks/run.sh validate-langevin`)."""
import math
import time

import numpy as np
from openmm import unit

from .common import (KB, block_mean, context as start_context, density, masses as masses_of, removes_cm, rigid_split,
                     water, water_integrator, write_csv)


def verdict(value, error, target, tolerance):
    """Whether value is within tolerance (relative) of target, as far as its error bar tells."""
    deviation, allowed = abs(value - target), tolerance * target
    if deviation <= allowed:
        return 'yes' if 3 * error <= allowed else 'yes (error bar larger than the tolerance)'
    if deviation - 3 * error <= allowed:
        return 'not resolved (%.1f SE from the target)' % (deviation / error)
    return 'no (%.1f SE outside the tolerance)' % ((deviation - allowed) / error)


def oo_peak(frames, oxygens, box):
    """Height and position of the first peak of the O-O g(r)."""
    edges = np.arange(0.2, 0.45, 0.005)
    counts = np.zeros(len(edges) - 1)
    for x in frames:
        o = x[oxygens]
        for i in range(len(o) - 1):
            d = o[i + 1:] - o[i]
            d -= box * np.round(d / box)
            r = np.sqrt((d * d).sum(axis=1))
            counts += np.histogram(r, edges)[0]
    n = len(oxygens)
    shell = 4 / 3 * math.pi * (edges[1:] ** 3 - edges[:-1] ** 3)
    g = counts / (len(frames) * 0.5 * n * (n - 1) / box ** 3 * shell)
    k = int(np.argmax(g))
    return g[k], 0.5 * (edges[k] + edges[k + 1])


def run_water(method, barostat, equilibrate, production, sample, seed, log):
    system, positions, bodies = water(barostat_seed=0 if barostat else None)  # bodies: every residue, the waters
    integrator = water_integrator(method, 2, seed)
    context = start_context(system, integrator, positions, (300 * unit.kelvin, seed))
    masses, cm = masses_of(system), removes_cm(system)
    dof = 6 * len(bodies) - (3 if cm else 0)
    start = time.time()
    integrator.step(equilibrate)
    series = {'T': [], 'Ttrans': [], 'Trot': [], 'U': [], 'density': []}
    frames = []
    for k in range(production // sample):
        integrator.step(sample)
        state = context.getState(getVelocities=True, getEnergy=True, getPositions=(k % 10 == 0))
        v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometers / unit.picosecond)
        kt, kr = rigid_split(v, masses, bodies)
        series['T'].append(2 * (kt + kr) / (dof * KB))
        series['Ttrans'].append(2 * kt / ((dof - 3 * len(bodies)) * KB))
        series['Trot'].append(2 * kr / (3 * len(bodies) * KB))
        series['U'].append(state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole) / len(bodies))
        series['density'].append(density(state, masses))
        if k % 10 == 0:
            frames.append(state.getPositions(asNumpy=True).value_in_unit(unit.nanometers))
    result = {key: block_mean(values) for key, values in series.items()}
    if not barostat:
        result['peak'] = oo_peak(frames[::2], [b[0] for b in bodies],
                                 state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometers)[0][0])
    log('%-22s %s %d+%d steps in %.0f s' % (method, 'NPT' if barostat else 'NVT', equilibrate, production,
                                            time.time() - start))
    return result


def run(quick, out, log):
    """Run the validation; write out + '.csv'; return the report as markdown lines."""
    scale = 0.02 if quick else 1.0
    nvt = dict(equilibrate=int(5000 * scale), production=int(20000 * scale), sample=20)
    npt = dict(equilibrate=int(10000 * scale), production=int(40000 * scale), sample=50)
    rows = []
    report = ['\n## Langevin dynamics with M-RATTLE: validation against LangevinMiddle + SETTLE\n',
              'OpenMM\'s tip3p.pdb, %s. The method: `docs/benchmarks.md`, "Langevin".\n' % (
                  'a **quick** smoke run: too short to conclude anything' if quick else
                  'NVT %d ps after %d ps, NPT %d ps after %d ps' % (
                      nvt['production'] * 0.002, nvt['equilibrate'] * 0.002,
                      npt['production'] * 0.002, npt['equilibrate'] * 0.002))]
    results = {}
    for method in ('M-RATTLE Langevin', 'LangevinMiddle + SETTLE'):
        results[(method, 'NVT')] = run_water(method, False, seed=1, log=log, **nvt)
        results[(method, 'NPT')] = run_water(method, True, seed=2, log=log, **npt)
    report += ['| Quantity | M-RATTLE Langevin | LangevinMiddle + SETTLE | Target | Verdict |', '|---|---|---|---|---|']

    def fmt(pair, digits=2):
        return '%.*f +- %.*f' % (digits, pair[0], digits, pair[1])

    def row(quantity, a, b):
        rows.append(dict(quantity=quantity, mrattle=a[0], mrattle_error=a[1], settle=b[0], settle_error=b[1]))

    m, s = results[('M-RATTLE Langevin', 'NVT')], results[('LangevinMiddle + SETTLE', 'NVT')]
    for key, name, tolerance in (('T', 'kinetic temperature (K)', 0.01), ('Ttrans', 'translational temperature (K)', 0.02),
                                 ('Trot', 'rotational temperature (K)', 0.02)):
        report.append('| %s | %s | %s | 300 +- %d%% | %s |' % (name, fmt(m[key]), fmt(s[key]), round(100 * tolerance),
                                                             verdict(m[key][0], m[key][1], 300, tolerance)))
        row(key, m[key], s[key])
    difference, combined = m['U'][0] - s['U'][0], math.hypot(m['U'][1], s['U'][1])
    report.append('| potential energy per molecule (kJ/mol) | %s | %s | equal within 3 combined SE | %s |' % (
        fmt(m['U'], 3), fmt(s['U'], 3), 'difference %.3f = %.1f SE: %s' % (
            difference, abs(difference) / combined, 'consistent' if abs(difference) <= 3 * combined else 'NOT consistent')))
    row('U', m['U'], s['U'])
    peak_m, peak_s = m['peak'], s['peak']
    report.append('| O-O g(r) first peak: height (position, nm) | %.3f (%.4f) | %.3f (%.4f) | heights within 3%% | '
                  'differ by %.1f%% (no error bar: one histogram per run) |' % (
                      peak_m[0], peak_m[1], peak_s[0], peak_s[1], 100 * abs(peak_m[0] / peak_s[0] - 1)))
    row('gOO_peak', (peak_m[0], ''), (peak_s[0], ''))
    dm, ds = results[('M-RATTLE Langevin', 'NPT')]['density'], results[('LangevinMiddle + SETTLE', 'NPT')]['density']
    report.append('| density at 1 bar (g/mL) | %s | %s | within 0.005 g/mL | difference %.4f +- %.4f |' % (
        fmt(dm, 4), fmt(ds, 4), dm[0] - ds[0], math.hypot(dm[1], ds[1])))
    row('density', dm, ds)

    write_csv(out + '.csv', rows)
    return report


