"""Cost of one integration step with forces excluded (the only force a zero CustomExternalForce): N rigid
bodies of k atoms on a 1.2 nm lattice, M-RATTLE and the splitting method against OpenMM's Verlet, SETTLE
and CCMA, timed in interleaved batches so that the ratios of one run share the machine's load
(integrators, targets and what limits them: docs/benchmarks.md)."""
import math
import statistics
import time

import numpy as np
import openmm

import mrattle
from . import common

# Ratios and their targets: (name, numerator, denominator, test), at the first thread count.
TARGETS = [("mrattle/verlet", "mrattle", "verlet", "<=1.5"), ("mrattle/splitting", "mrattle", "splitting", "<=1.0"),
           ("verlet_ccma/mrattle", "verlet_ccma", "mrattle", ">=2"),
           ("mrattle_allpairs/mrattle", "mrattle_allpairs", "mrattle", "<=1.10"),
           ("mrattle/verlet_settle", "mrattle", "verlet_settle", "<=1.0")]


def body_shape(k):
    """Sites (nm, about the centre of mass) and masses of a body: k = 5 a tetrahedral CX4, k = 3 a bent
    triatomic (a TIP3P-shaped water), else k atoms on a helix with mixed masses (irregular, asymmetric)."""
    if k == 5:
        s = 0.109 / math.sqrt(3.0)
        sites, masses = [[0, 0, 0], [s, s, s], [s, -s, -s], [-s, s, -s], [-s, -s, s]], [12.011] + [1.008] * 4
    elif k == 3:
        sites, masses = [[0, 0, 0], [0.09572, 0, 0], [-0.02399, 0.09267, 0]], [15.999, 1.008, 1.008]
    else:
        j = np.arange(k)
        radius, angle = 0.15 + 0.15 * ((j * 7) % 5) / 4.0, 2.4 * j
        sites = np.column_stack([radius * np.cos(angle), radius * np.sin(angle), -0.3 + 0.6 * j / max(k - 1, 1)])
        masses = [(12.011, 1.008, 15.999)[i % 3] for i in j]
    sites, masses = np.array(sites, float), np.array(masses)
    return sites - masses.dot(sites) / masses.sum(), masses


def build(bodies, sites, masses, pairs):
    """The System of `bodies` bodies with no constraints, 9 of a tetrahedron's 10 pair distances
    ('rigidifying': every pair but the first H-H) or all pairs constrained; and the constraints per body."""
    k = len(masses)
    kept = [(i, j) for i in range(k) for j in range(i + 1, k)
            if pairs == "all" or (pairs == "rigidifying" and (i, j) != (1, 2))]
    system = openmm.System()
    for b in range(bodies):
        for m in masses:
            system.addParticle(m)
        for i, j in kept:
            system.addConstraint(b * k + i, b * k + j, float(np.linalg.norm(sites[i] - sites[j])))
    if pairs == "rigidifying":
        # CCMA couples two constraints that share an atom through their angle, taken from a closing
        # constraint or else a HarmonicAngleForce; with neither it diverges in the first step. So every
        # such angle, zero force constant, in force group 1, which the integrator does not evaluate.
        angles = openmm.HarmonicAngleForce()
        for b, c, i, j in ((b, c, i, j) for b in range(bodies) for c in range(k) for i in range(k)
                           for j in range(i + 1, k)):
            if c not in (i, j) and {tuple(sorted(p)) for p in ((i, c), (j, c))} <= set(kept) and (i, j) not in kept:
                u, w = sites[i] - sites[c], sites[j] - sites[c]
                angle = math.acos(u.dot(w) / math.sqrt(u.dot(u) * w.dot(w)))
                angles.addAngle(b * k + i, b * k + c, b * k + j, angle, 0.0)
        angles.setForceGroup(1)
        system.addForce(angles)
    zero = openmm.CustomExternalForce("0*x")
    zero.addParticle(0, [])
    system.addForce(zero)
    return system, len(kept)


def batch_steps(integrator, seconds, warmup, timed):
    """Steps that take about `seconds`: `warmup` steps, then `timed` steps timed."""
    integrator.step(warmup)
    start = time.perf_counter()
    integrator.step(timed)
    return max(1, int(seconds / max((time.perf_counter() - start) / timed, 1e-9)))


def variants(k, names=None):
    """(integrator, constrained pairs) of each configuration timed for bodies of k atoms."""
    out = [("verlet", None), ("mrattle", None), ("splitting", None)]
    out += [("mrattle_allpairs", "all"), ("verlet_ccma", "rigidifying")] if k == 5 else []
    out += [("verlet_settle", "all")] if k == 3 else []
    return [v for v in out if names is None or v[0] in names]


def run(platforms, body_counts, atoms, repeats, batch_seconds, log, threads=(1,), names=None):
    """Median time per 2 fs step of every configuration; returns (timing rows, ratio rows). On the CPU
    platform each thread count after the first adds verlet, mrattle and splitting with that many threads."""
    timings, ratios = [], []
    for platform_name in platforms:
        counts = list(threads) if platform_name == "CPU" else [1]
        for k in atoms:
            sites, masses = body_shape(k)
            for n in body_counts:
                side = math.ceil(round(n ** (1 / 3), 9))
                centres = 1.2 * np.array([(b % side, (b // side) % side, b // side ** 2) for b in range(n)])
                positions = (centres[:, None, :] + sites[None, :, :]).reshape(-1, 3)
                runs = {}
                for count, (name, pairs) in ((c, v) for c in counts for v in variants(k, names)):
                    if count != counts[0] and name not in ("verlet", "mrattle", "splitting"):
                        continue
                    system, constraints = build(n, sites, masses, pairs)
                    if name.startswith("verlet"):
                        integrator = openmm.VerletIntegrator(0.002)
                        integrator.setIntegrationForceGroups({0})
                    else:
                        integrator = common.make_integrator("splitting" if name == "splitting" else "M-RATTLE", 0.002,
                                                            bodies=[list(range(b * k, b * k + k)) for b in range(n)])
                    context = common.context(system, integrator, positions, (300, 1), platform_name, count)
                    runs[name, count] = dict(constraints=constraints, steps=batch_steps(integrator, batch_seconds, 5, 10),
                                             integrator=integrator, context=context)
                seconds = common.interleaved({key: r["integrator"] for key, r in runs.items()},
                                             {key: r["steps"] for key, r in runs.items()}, repeats)
                medians = {}
                for (name, count), r in runs.items():
                    m = medians[name, count] = statistics.median(seconds[name, count])
                    state = r["context"].getState(getPositions=True, getEnergy=True, groups={0})
                    finite = bool(np.isfinite(state.getPositions(asNumpy=True)._value).all()) and math.isfinite(
                        state.getKineticEnergy()._value)  # a diverged run is timed but flagged
                    timings.append(dict(platform=platform_name, integrator=name, atoms_per_body=k, bodies=n,
                                        atoms=n * k, constraints_per_body=r["constraints"], steps_per_batch=r["steps"],
                                        batches=repeats, median_us_per_step=m * 1e6,
                                        min_us_per_step=min(seconds[name, count]) * 1e6,
                                        max_us_per_step=max(seconds[name, count]) * 1e6,
                                        median_ns_per_atom_step=m * 1e9 / (n * k), finite="yes" if finite else "no",
                                        threads=count))
                row = dict(platform=platform_name, atoms_per_body=k, bodies=n)
                for label, a, b, target in TARGETS:
                    if (a, counts[0]) in medians and (b, counts[0]) in medians:
                        value = medians[a, counts[0]] / medians[b, counts[0]]
                        met = value <= float(target[2:]) if target[0] == "<" else value >= float(target[2:])
                        ratios.append(dict(row, ratio=label, value=value, target=target, met="yes" if met else "no"))
                for count in counts[1:]:  # the speed-up from threads
                    for name in [n for n in ("mrattle", "splitting") if (n, count) in medians]:
                        value = medians[name, counts[0]] / medians[name, count]
                        target = ">=1.7" if n >= 3000 and name == "mrattle" else "-"
                        ratios.append(dict(row, ratio="%s threads %d/%d" % (name, counts[0], count), value=value,
                                           target=target, met="-" if target == "-" else "yes" if value >= 1.7 else "no"))
                log("  cost %s k=%d N=%d: %s" % (platform_name, k, n, ", ".join(
                    "%s %.1f us" % (name if t == counts[0] else "%s (%d threads)" % (name, t), m * 1e6)
                    for (name, t), m in medians.items())))
    six = lambda v: float("%.6g" % v) if isinstance(v, float) else v  # noqa: E731  (6 significant digits)
    return [{k: six(v) for k, v in r.items()} for r in timings], [{k: six(v) for k, v in r.items()} for r in ratios]


def paper_systems(platforms, batches, batch_seconds, log):
    """Median time per 2 fs step of M-RATTLE and the splitting method on the paper's systems, forces included
    (one rigid benzene, the 27-benzene cluster; the CPU platform with one thread), interleaved batches."""
    from openmm import unit
    rows = []
    for label, model in (("isolated benzene", mrattle.models.benzene()),
                         ("27-benzene cluster", mrattle.models.benzeneCluster(temperature=250 * unit.kelvin, seed=1))):
        bodies = mrattle.rigidBodies(model.topology, model.system, 'BNZ')
        x = np.array(model.positions.value_in_unit(unit.nanometer))
        v = common.rigid_velocities(model.system, x, bodies, 300.0, seed=2)
        for platform_name in platforms:
            runs, contexts, steps = {}, [], {}
            for method in ("M-RATTLE", "splitting"):
                runs[method] = integrator = common.make_integrator(method, 2 * common.FS, bodies=bodies)
                contexts.append(common.context(model.system, integrator, x, v, platform_name, 1))
                steps[method] = batch_steps(integrator, batch_seconds, 10, 20)
            per_step = {m: statistics.median(s) for m, s in common.interleaved(runs, steps, batches).items()}
            rows += [{"system": label, "platform": platform_name, "method": m, "us_per_step": per_step[m] * 1e6}
                     for m in runs]
            log("  %-20s %-9s M-RATTLE %.1f us/step, splitting %.1f us/step (ratio %.2f)" % (
                label, platform_name, rows[-2]["us_per_step"], rows[-1]["us_per_step"],
                rows[-2]["us_per_step"] / rows[-1]["us_per_step"]))
    return rows


def plot(timings, path):
    platforms = sorted({r["platform"] for r in timings})
    fig, axes = common.panels(len(platforms), 5.5)
    k = 5 if any(int(r["atoms_per_body"]) == 5 for r in timings) else int(timings[0]["atoms_per_body"])
    for ax, platform in zip(axes, platforms):
        rows = [r for r in timings if r["platform"] == platform and int(r["atoms_per_body"]) == k]
        for integrator, threads in sorted({(r["integrator"], int(r["threads"])) for r in rows}):
            pts = sorted((int(r["bodies"]), float(r["median_us_per_step"])) for r in rows
                         if r["integrator"] == integrator and int(r["threads"]) == threads)
            label = integrator if threads == 1 else "%s (%d threads)" % (integrator, threads)
            ax.loglog([p[0] for p in pts], [p[1] for p in pts], "o--" if threads != 1 else "o-", label=label)
        ax.set_xlabel("number of rigid bodies (k = %d atoms each)" % k)
        ax.set_ylabel("time per step (microseconds, median)")
        ax.set_title(platform)
        ax.legend(fontsize=8)
    common.save_figure(fig, path)


def main(argv=None):
    """`./benchmarks/run.sh speed` on CPU or Reference: the cost per step against OpenMM's integrators."""
    import argparse
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--platforms", default="CPU")
    p.add_argument("--bodies", default="1000,3000")
    p.add_argument("--atoms", default="3,5")
    p.add_argument("--integrators", default=None, help="comma-separated (default all)")
    p.add_argument("--threads", default="1,2")
    p.add_argument("--repeats", type=int, default=9)
    p.add_argument("--batch-seconds", type=float, default=0.05)
    p.add_argument("--out", required=True, help="folder for step_cost.csv and step_cost-ratios.csv")
    a = p.parse_args(argv)
    ints = lambda text: [int(x) for x in text.split(",")]  # noqa: E731
    timings, ratios = run(a.platforms.split(","), ints(a.bodies), ints(a.atoms), a.repeats, a.batch_seconds,
                          lambda m: print(m, flush=True), ints(a.threads),
                          a.integrators.split(",") if a.integrators else None)
    common.write_csv(a.out + "/step_cost.csv", timings)
    common.write_csv(a.out + "/step_cost-ratios.csv", ratios)
    print("\n".join([",".join(ratios[0])] + [",".join(map(str, r.values())) for r in ratios]) if ratios else "")
    return 0 if all(r["finite"] == "yes" for r in timings) else 2


if __name__ == "__main__":
    raise SystemExit(main())
