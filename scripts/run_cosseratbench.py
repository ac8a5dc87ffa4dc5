"""Runs cosseratbench's experiments with softrod and the peers, and writes
docs/benchmarks.md from the saved runs. Started by scripts/cosseratbench.sh,
which prepares the virtual environment; see there for the options."""

from __future__ import annotations

import argparse
import datetime
import importlib.metadata
import json
import os
import platform
import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np

os.environ.setdefault("MPLBACKEND", "Agg")
import matplotlib.pyplot as plt  # noqa: E402
from cosseratbench import registry, runs, variations  # noqa: E402
from cosseratbench.trajectory import Trajectory  # noqa: E402

REPO = Path(__file__).resolve().parents[1]
SOLVERS = ("softrod", "pyelastica", "mujoco", "dismech")
#: A quick check runs each experiment at this fraction of its resolution.
QUICK_FRACTION = 5
COLOURS = {"softrod": "tab:red", "pyelastica": "tab:blue", "mujoco": "tab:green",
           "dismech": "tab:purple"}

#: Why softrod's number differs from PyElastica's where it is worse: the
#: cause, as measured (the report adds the live numbers).
EXPLAIN = {
    ("catenary", "sag_error"): (
        "the reference is a perfectly flexible cable; a rod with bending stiffness "
        "sags less. The planar elastica with bending and stretch (cosseratbench's own "
        "crossing reference, whose rope is this cable) sags {bending:.2e} less than the "
        "flexible catenary, and softrod's sag is {softrod_vs_elastica:.1e} from the "
        "elastica's: softrod's error is the bending the reference leaves out, converged "
        "in the resolution (docs: the test `test_catenary_against_the_elastica_with_bending`). "
        "PyElastica's smaller number is its discretization error partly cancelling it."
    ),
    ("catenary", "shape_error"): (
        "as for the sag: the flexible reference leaves out bending, which softrod "
        "resolves (the shape error is converged in the resolution)."
    ),
    ("cantilever", "settling_residual"): (
        "both settle through the same mass-proportional damping at the rate 2w, with w "
        "the Euler-Bernoulli estimate of the slowest mode (1.112 rad/s). softrod's 20 "
        "pieces reproduce that mode, so it is damped exactly critically and its speed "
        "after the suddenly applied load is d w^2 t e^(-w t): 3.6e-6 rod lengths per "
        "second at t = 10 s for the static deflection d = P L^3/(3 E I) = 1.99 cm; "
        "softrod's converged residual is 3.71e-6 (Radau IIA at rtol 1e-7; 3.70e-6 with "
        "ESDIRK at rtol 1e-6), and the rule's ESDIRK at rtol 1e-3 adds its path error "
        "(3.8e-6 with Radau IIA at the same tolerance). PyElastica's beam is stiffer (its "
        "clamped element held rigid: the tip settles at 1.844 cm), so under the same rate "
        "its slowest mode is slightly underdamped: its tip overshoots (the tip speed "
        "changes sign near t = 8.7 s in a 401-frame run of cosseratbench's PyElastica "
        "adapter) and its speed decays as e^(-w t) without the factor w t = 11, ending "
        "near a turning point. A smaller residual here is not a closer equilibrium."
    ),
    ("twist", "n/a"): (
        "cosseratbench fits the critical twist to the three growing rods nearest the "
        "threshold; at this resolution fewer than three of softrod's rods grow, as its "
        "discrete critical twist lies above the reference's by more than the levels' 2 % "
        "spacing (it converges to the reference as the pieces are refined)."
    ),
    ("crossing", "lift_error"): (
        "the symmetric crossing is an unstable equilibrium of softrod's model at this resolution, and the run leaves it. Measured (docs/performance.md, \"The crossing at 51 pieces\"): softrod's statics from the symmetric start finds the symmetric equilibrium with the upper rope's middle at z = -0.2778981 m against the elastica reference's -0.2779154 (lift error 0.02 %, PyElastica's run 0.28 %), but its linearization there has one real positive eigenvalue (none at 21 pieces, -0.48/s at 31, +0.13/s at 41, +0.52/s at 51, +0.82/s at 61, +1.26/s at 81), whose mode slides the contact along the upper rope as the lower rope swings sideways; the dynamics follow it (a 1 mm sideways push grows in its own direction at rtol 1e-5; at the rule's rtol 1e-3 the contact's onset kicks it the same way whatever the push) into an asymmetric equilibrium with the lower rope's middle 3.1 cm aside. The destabilizing term is the geometric stiffness -f d''(q) of the exact closest points of the two curved centrelines (checked against a brute-force minimization of the distance, and the contact stiffness is symmetric: conservative; docs/theory-contact.md CT41); PyElastica and MuJoCo take contact between straight segments, and from the same push return to symmetric (PyElastica at 51 and 101 elements). Whether the continuum problem with smooth curved contact is stable, and so which model is right about it, is not settled."
    ),
    ("crossing", "shape_error"): (
        "as for the lift: the run ends in the asymmetric equilibrium that the unstable "
        "symmetric one decays into."
    ),
    ("catenary", "settling_residual"): (
        "the same mass-proportional damping; both residuals are below 2e-7 rod lengths "
        "per second, what the damping leaves of the transient (why softrod's is the "
        "larger is not established)."
    ),
}
#: Why softrod's rods pass further into each other (or into an obstacle) than
#: PyElastica's, keyed by (experiment, observation).
EXPLAIN_OVERLAP = {
    ("capstan", "max_penetration"): (
        "softrod's contact is a penalty sized to hold each contact point's weight within "
        "1 % of the radius and raised to the force it carries (docs/theory-contact.md CT3, "
        "CT15): here 0.14 % of the rope's radius, within that bound. PyElastica's reported "
        "0 was not analysed."
    ),
    ("crossing", "max_rod_overlap"): (
        "softrod's own contact reports about 1e-5 m of penetration (0.2 % of the radius) "
        "where the ropes press (its contacts at 0.1-0.4 s of a 51-piece run); cosseratbench "
        "measures between the straight segments joining the output nodes, which cut the "
        "corner of a curved rope, and the run ends in the asymmetric state (see the lift). "
        "Not analysed further."
    ),
    ("twist", "max_rod_overlap"): (
        "the six rods run as six simulations (one model of all six would have dense "
        "Newton matrices of 1806 coordinates, docs/performance.md), so they cannot touch "
        "one another: the plectoneme of a buckled rod grows into its neighbour, which "
        "cosseratbench's measure counts (it takes every pair of rods). Within each rod "
        "(self contact) the deepest overlap of this run is {self_overlap:.2g} radii."
    ),
}
#: Why softrod's wall time is longer than PyElastica's where it is.
EXPLAIN_TIME = {
    "capstan": (
        "the rope's ~150 touching points are stiff penalty contacts with anchored, "
        "sticking friction (docs/theory-contact.md): the quasi-static rule's ESDIRK takes "
        "steps of 1.1 ms on average (1770 over the 2 s, 508 rejected, measured with "
        "softrod's CLI on the adapter's scene at overhang 0.95), each with Newton "
        "iterations on the O(n) structured matrix re-linearized at every iterate (CT27) "
        "and, where that fails, a dense exact Jacobian (132 over the run): about 22 ms "
        "of CPU a step against PyElastica's explicit 0.22 ms (docs/performance.md, "
        "\"Contact-heavy scenes\")."
    ),
    "catenary": (
        "a cable pinned at both ends is a closed chain for softrod (a spherical joint "
        "and a ball closure), whose Newton matrices are dense (O(n^3) in the coordinates, "
        "six per piece; the Jacobian itself is analytic, docs/theory-derivatives.md): "
        "the quasi-static rule's ESDIRK refreshes and factors them a few hundred times "
        "over the settle (its steps end on the 101 output frames, CD10). Radau IIA, the "
        "rule on closed chains before CD10, took 15.6 s here. softrod's structured O(n) "
        "Newton solve of closed chains (the KKT form, CD5-CD8) is off by default and not "
        "reachable from Python."
    ),
    "crossing": (
        "both ropes are closed chains (a spherical joint and a ball closure each) with "
        "rod-rod contact: the quasi-static rule's ESDIRK with the loops projected after "
        "every step (D121) factors the dense Newton matrices of the ~620 coordinates a few "
        "hundred times (measured with softrod's CLI on the adapter's scene: 1287 steps, "
        "229 rejected, 398 dense Jacobians, 84 CPU s; docs/performance.md, \"Closed chains: "
        "projection onto the closures\")."
    ),
    "twist": (
        "each rod is a closed chain (a weld to a carriage on a prescribed drive) with "
        "self contact, run by the quasi-static rule's ESDIRK with its loop projected "
        "back onto the weld after every step (docs/theory.md D121) and dense Newton "
        "matrices (as the catenary's); the six rods run as six simulations one after the "
        "other, and the rods that buckle cost most of it: the rod held at 1.06 of the "
        "critical twist took 63.5 CPU s alone (commit 41ec6b8; 112.7 s with Radau IIA, the "
        "rule on closed models with contact before the projection) as it grows sideways "
        "and wraps into a plectoneme that reaches itself. PyElastica's explicit step "
        "costs 26 microseconds."
    ),
}

#: Experiments the adapter can express (it declares their capabilities) but
#: whose softrod runs this report leaves out, with the reason measured; run
#: them with --with-slow.
NOT_RUN = {
    "pile": (
        "not run in this report: the adapter expresses it (contact tables, "
        "docs/theory-contact.md) and softrod runs it, but far too slowly. Measured at its "
        "100 pieces with the adapter's rule (ESDIRK, steps ending on the output frames; "
        "softrod's CLI on the adapter's scene, release build, the shared 2-core VM): the "
        "first 0.3 s of its 4.45 s (the rope falling, its tip landing) take 39 CPU s, the "
        "first 1.3 s took 1094 CPU s (5230 steps, 5267 rejected, 3921 dense Jacobians of "
        "the 600 coordinates): about 1000 CPU s per simulated second once the rope lies "
        "on the floor, so the whole run would take more than an hour. The steps (0.22 ms "
        "on average, about as many rejected as accepted) are limited by the Newton "
        "iteration at the touching points, and most fall back on the exact dense "
        "Jacobian, whose contact terms and LU take about 70 % of the time (docs/performance.md, \"Contact-heavy scenes\")."
    ),
}


def parse() -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("experiment", nargs="*", help="experiments to run (default: all)")
    parser.add_argument("--quick", action="store_true",
                        help=f"1/{QUICK_FRACTION} of each resolution; writes out/cosseratbench/quick")
    parser.add_argument("--vary", action="append", default=[],
                        help="also run the variants of this parameter or option ('all': every one)")
    parser.add_argument("--solver", action="append", help="solvers (default: all installed)")
    parser.add_argument("--report-only", action="store_true", help="run nothing")
    parser.add_argument("--with-slow", action="store_true",
                        help="also run softrod on the experiments of NOT_RUN")
    return parser.parse_args()


def installed(name: str) -> bool:
    try:
        registry.load_solver(name)
    except ImportError:
        return False
    return True


def main() -> None:
    args = parse()
    names = registry.names(registry.EXPERIMENTS)
    base = REPO / "out" / "cosseratbench"
    if args.quick:
        results, report, images = base / "quick" / "results", base / "quick" / "benchmarks.md", \
            base / "quick" / "images"
    else:
        results, report = base / "results", REPO / "docs" / "benchmarks.md"
        images = REPO / "docs" / "images" / "benchmarks"
    solvers = args.solver or [s for s in SOLVERS if installed(s)]
    if not args.report_only:
        for name in args.experiment or names:
            experiment = registry.load_experiment(name)
            n = max(experiment.n_elements // QUICK_FRACTION, 4) if args.quick else None
            if args.quick and experiment.n_elements % 2 and n % 2 == 0:
                n += 1  # keep an odd resolution odd (the crossing's contact node)
            # Each name applies to the experiments that have it.
            vary = [v for v in args.vary if v == "all" or v in variations.sweepable(experiment)]
            run_by = [s for s in solvers
                      if not (s == "softrod" and name in NOT_RUN and not args.with_slow)]
            tasks = runs.plan([experiment], run_by, vary, n, results)
            runs.execute(tasks, jobs=1)
    write_report(results, report, images, names, quick=args.quick)
    print(f"wrote {report.relative_to(REPO)}")


# -- the report --------------------------------------------------------------


def versions() -> list[tuple[str, str]]:
    found = []
    for package in ("softrod", "cosseratbench", "pyelastica", "mujoco", "dismech-python",
                    "numpy", "scipy", "numba", "matplotlib"):
        try:
            found.append((package, importlib.metadata.version(package)))
        except importlib.metadata.PackageNotFoundError:
            found.append((package, "not installed"))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=REPO,
                            capture_output=True, text=True).stdout.strip()
    # The report and its plots are this script's output, not softrod: a
    # rewrite over a previous one is not a modified softrod.
    dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", ".",
                            ":!docs/benchmarks.md", ":!docs/images/benchmarks"], cwd=REPO,
                           capture_output=True, text=True).stdout.strip()
    found[0] = ("softrod", f"{found[0][1]} (commit {commit}{', modified' if dirty else ''}, "
                "release build)")
    return found


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} logical cores, {platform.system()} {platform.release()}, " \
           f"Python {platform.python_version()}"


def load_runs(results: Path, name: str) -> list[tuple[dict, dict]]:
    """(experiment.json, result.json) of every saved run of ``name``, the
    ordinary case first."""
    found = []
    for description in sorted((results / name).glob("*/experiment.json")):
        variant = json.loads(description.read_text())
        for path in sorted(description.parent.glob("*/result.json")):
            found.append((variant, json.loads(path.read_text()) | {"_dir": str(path.parent)}))
    order = {s: i for i, s in enumerate(SOLVERS)}
    found.sort(key=lambda vr: (bool(vr[0]["varied"]), vr[0]["varied"] and
                               sorted(vr[0]["varied"].items()), order.get(vr[1]["solver"], 9)))
    return found


def fmt(value, digits: int = 3) -> str:
    if value is None:
        return "n/a"
    if isinstance(value, float):
        if value != value:
            return "n/a"
        return f"{value:.{digits}e}"
    return str(value)


def variant_name(variant: dict) -> str:
    return ", ".join(f"{k} = {v:g}" for k, v in sorted(variant["varied"].items())) or "default"


def outcome(summary: dict) -> str:
    if summary["outcome"] == "unsupported":
        return "unsupported: " + "; ".join(summary["missing"])
    if summary["outcome"] == "diverged":
        when = summary.get("diverged_at")
        return f"diverged{f' at {when:.3g} s' if when is not None else ''}: {summary['failure']}"
    return "completed"


def worse(metric: str, ours: float | None, theirs: float | None) -> bool:
    """Whether softrod's ``metric`` is worse than the peer's, for the metrics
    with a right answer (errors, residuals, the amplitude change)."""
    if ours is None or theirs is None:
        return False
    if metric.endswith("_error") or metric in ("settling_residual", "amplitude_change"):
        return abs(ours) > abs(theirs)
    return False


def bending_numbers() -> dict:
    """The catenary's bending effect, measured live: the elastica with bending
    (cosseratbench's crossing reference, the catenary's cable) against the
    flexible catenary and against softrod's converged statics."""
    from cosseratbench.experiments import catenary, crossing

    from softrod import cosseratbench_solver as adapter

    scenario = registry.load_experiment("catenary").scenario
    flexible = catenary._reference(scenario)[:, 2].min()
    elastica = crossing._mid_height(scenario.rods[0].material.youngs_modulus, 0.0)
    part = adapter._parts(scenario, 100, 0.0)[0]
    q = part.sim.statics().q
    s = np.linspace(0.0, scenario.rods[0].length, 101)
    sag = part.sim.pose(0, s, q)[:, 2, 3].min()
    return {"bending": abs((elastica - flexible) / flexible),
            "softrod_vs_elastica": abs((sag - elastica) / elastica)}


def self_overlap(name: str, variant: dict, summary: dict) -> float:
    """cosseratbench's max_rod_overlap of each rod with itself alone (the largest):
    what self contact let through, without the pairs of different rods."""
    from cosseratbench.experiment import max_rod_overlap

    scenario = registry.load_experiment(name).scenario_for(
        **{k: v for k, v in variant["varied"].items() if k in variant["values"]})
    traj = Trajectory.load(Path(summary["_dir"]) / "trajectory.npz")
    worst = 0.0
    for rod, positions, directors in zip(scenario.rods, traj.positions, traj.directors):
        alone = replace(scenario, rods=(rod,))
        one = Trajectory(traj.times, (positions,), (directors,))
        value = max_rod_overlap(alone, one)
        if value == value:
            worst = max(worst, value)
    return worst


def plot(name: str, variant: dict, runs_: list[dict], path: Path) -> bool:
    """The final shapes beside the reference, and the motion over time."""
    trajectories = {}
    for summary in runs_:
        file = Path(summary["_dir"]) / "trajectory.npz"
        if summary["outcome"] == "completed" and file.exists():
            trajectories[summary["solver"]] = Trajectory.load(file)
    if not trajectories:
        return False
    fig, (shape_ax, time_ax) = plt.subplots(1, 2, figsize=(11, 4.2))
    finals = np.concatenate([p[-1] for t in trajectories.values() for p in t.positions])
    spread = finals.max(axis=0) - finals.min(axis=0)
    axes = sorted(np.argsort(spread)[-2:])
    labels = "xyz"
    for solver, traj in trajectories.items():
        for i, positions in enumerate(traj.positions):
            final = positions[-1]
            shape_ax.plot(final[:, axes[0]], final[:, axes[1]], "o-", ms=2, lw=1,
                          color=COLOURS.get(solver), label=solver if i == 0 else None)
    for k, curve in enumerate(variant.get("reference") or []):
        curve = np.asarray(curve)
        shape_ax.plot(curve[:, axes[0]], curve[:, axes[1]], "k--", lw=1,
                      label="reference" if k == 0 else None)
    shape_ax.set_xlabel(f"{labels[axes[0]]} [m]")
    shape_ax.set_ylabel(f"{labels[axes[1]]} [m]")
    shape_ax.set_aspect("equal", adjustable="datalim")
    shape_ax.set_title("final shape")
    shape_ax.legend(fontsize=8)

    scenario = registry.load_experiment(name).scenario_for(
        **{k: v for k, v in variant["varied"].items() if k in variant["values"]})
    for solver, traj in trajectories.items():
        t = traj.times
        if name == "pendulum":
            time_ax.plot(t, traj.positions[0][:, -1, 0], color=COLOURS.get(solver), label=solver)
            time_ax.set_ylabel("free end x [m]")
        elif name == "twist":
            from cosseratbench.experiments import twist

            for i, (rod, positions) in enumerate(zip(scenario.rods, traj.positions)):
                time_ax.semilogy(t, np.maximum(twist._sideways(rod, positions), 1e-12),
                                 color=COLOURS.get(solver), lw=0.8,
                                 label=solver if i == 0 else None)
            time_ax.set_ylabel("sideways distance per rod [m]")
        elif name == "capstan":
            light = traj.positions[0][:, 0, 2]
            time_ax.plot(t, light - light[0], color=COLOURS.get(solver), label=solver)
            time_ax.set_ylabel("light end rise [m]")
        else:
            speed = [np.linalg.norm(np.diff(p, axis=0), axis=2).max(axis=1) / np.diff(t)
                     / rod.length for rod, p in zip(scenario.rods, traj.positions)]
            time_ax.semilogy(t[1:], np.maximum(np.max(speed, axis=0), 1e-14),
                             color=COLOURS.get(solver), label=solver)
            time_ax.set_ylabel("largest node speed [rod lengths / s]")
    time_ax.set_xlabel("t [s]")
    time_ax.legend(fontsize=8)
    fig.suptitle(f"{name} ({variant_name(variant)})")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return True


def write_report(results: Path, report: Path, images: Path, names: list[str], *,
                 quick: bool) -> None:
    now = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    lines = [
        "# softrod in cosseratbench: the outside benchmark",
        "",
        "Generated by `bash scripts/cosseratbench.sh` (never edited by hand): "
        "[cosseratbench](https://pypi.org/project/cosseratbench/) 0.3.0's experiments, "
        "each a physical scenario scored from the trajectory alone by the benchmark's own "
        "metrics, run through its own runner with softrod's adapter "
        "(`crates/softrod-py/python/softrod/cosseratbench_solver.py`, whose docstring says "
        "how a scenario becomes a softrod scene and which numerics it takes) and the "
        "adapters cosseratbench ships for PyElastica, MuJoCo's cable and dismech.",
        "",
        f"- Date: {now}" + (" (quick check: reduced resolutions)" if quick else ""),
        f"- Machine: {machine()}; runs one at a time, each timed by cosseratbench "
        "after a warm-up run (JIT compilation and loading excluded).",
        "- Versions: " + ", ".join(f"{p} {v}" for p, v in versions()),
        "- dismech-python is not on PyPI (installed from git only, Python >= 3.13, "
        "GPL-3.0), so it is not part of these runs.",
        "- Wall times are seconds on this shared 2-core machine: compare rows within a "
        "table. Metrics are as cosseratbench defines them (smaller errors are better); "
        "`max_penetration` is in rod radii, n/a where there is nothing to sink into.",
        "",
    ]
    summary_rows, shortfalls, totals = [], [], {}
    sections = []
    for name in names:
        found = load_runs(results, name)
        if not found:
            continue
        experiment = registry.load_experiment(name)
        variant0 = found[0][0]
        metrics = list(experiment.metrics)
        section = [f"## {name}", "", variant0["description"], "", variant0["notes"], ""]
        header = ["variant", "solver", "n", "outcome", *metrics, "max_penetration", "wall s"]
        section += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        defaults = {}
        for variant, summary in found:
            m = summary.get("metrics") or {}
            o = summary.get("observations") or {}
            row = [variant_name(variant), summary["solver"], str(summary["n_elements"]),
                   outcome(summary), *(fmt(m.get(k)) for k in metrics),
                   fmt(o.get("max_penetration")),
                   f"{summary['wall_time']:.3g}" if summary.get("wall_time") else "n/a"]
            section.append("| " + " | ".join(row) + " |")
            if not variant["varied"]:
                defaults[summary["solver"]] = summary
        section.append("")
        ours_settings = (defaults.get("softrod") or {}).get("settings") or {}
        if ours_settings:
            keys = ("integrator", "dt", "rtol", "atol", "damping", "damping_rate",
                    "simulations", "rod_contact")
            said = ", ".join(f"{k} {fmt(ours_settings[k], 3) if isinstance(ours_settings[k], float) else ours_settings[k]}"
                             for k in keys if k in ours_settings)
            section += [f"softrod's numerics (its `settings`, default variant): {said}; the "
                        f"largest distance of its fitted start from the scenario's: "
                        f"{fmt(max(ours_settings.get('start_fit_error', [0.0])), 2)} m.", ""]
        image = images / f"{name}.png"
        default_runs = [s for v, s in found if not v["varied"]]
        if plot(name, variant0, default_runs, image):
            rel = os.path.relpath(image, report.parent)
            section += [f"![{name}: final shapes and motion]({rel})", ""]
        ours, theirs = defaults.get("softrod"), defaults.get("pyelastica")
        row = [name]
        for solver in SOLVERS[:3]:
            s = defaults.get(solver)
            row.append(("not run" if solver == "softrod" and name in NOT_RUN else "—")
                       if s is None else (
                f"{s['wall_time']:.3g} s" if s["outcome"] == "completed" else s["outcome"]))
            if s is not None and s["outcome"] == "completed":
                totals[solver] = totals.get(solver, 0.0) + s["wall_time"]
        summary_rows.append(row)
        if ours and theirs and ours["outcome"] == theirs["outcome"] == "completed":
            notes = []
            for metric in metrics:
                a, b = ours["metrics"].get(metric), theirs["metrics"].get(metric)
                if a is None and b is not None:
                    notes.append(f"- `{metric}`: softrod n/a, PyElastica {fmt(b)}: "
                                 + EXPLAIN.get((name, "n/a"), "not computed."))
                elif worse(metric, a, b):
                    why = EXPLAIN.get((name, metric), "not explained yet.")
                    if "{bending" in why:
                        why = why.format(**bending_numbers())
                    notes.append(f"- `{metric}`: softrod {fmt(a)}, PyElastica {fmt(b)}: {why}")
            for key in ("max_penetration", "max_rod_overlap"):
                a = (ours.get("observations") or {}).get(key)
                b = (theirs.get("observations") or {}).get(key)
                if a is not None and b is not None and a > b and a > 1e-3:
                    why = EXPLAIN_OVERLAP.get((name, key), "not explained yet.")
                    if "{self_overlap" in why:
                        why = why.format(self_overlap=self_overlap(name, variant0, ours))
                    notes.append(f"- `{key}` (radii): softrod {fmt(a)}, PyElastica {fmt(b)}: {why}")
            if ours["wall_time"] > theirs["wall_time"] / 10:
                why = EXPLAIN_TIME.get(name, "")
                notes.append(f"- wall time: softrod {ours['wall_time']:.3g} s, PyElastica "
                             f"{theirs['wall_time']:.3g} s "
                             f"({ours['wall_time'] / theirs['wall_time']:.2g}x; the goal is "
                             f"0.1x){': ' + why if why else '.'}")
            if notes:
                shortfalls += [f"### {name}", "", *notes, ""]
        elif ours and ours["outcome"] != "completed":
            shortfalls += [f"### {name}", "", f"- softrod: {outcome(ours)}", ""]
        elif ours is None and name in NOT_RUN:
            shortfalls += [f"### {name}", "", f"- softrod: {NOT_RUN[name]}", ""]
        sections += section
    lines += ["## Summary: the default variant of each experiment", "",
              "| experiment | softrod | pyelastica | mujoco |", "|---|---|---|---|"]
    lines += ["| " + " | ".join(r) + " |" for r in summary_rows]
    lines += ["", "Total wall time of the completed default runs: " + ", ".join(
        f"{s} {t:.3g} s" for s, t in totals.items()) + " (over different sets of "
        "experiments where a solver could not run one).", ""]
    if shortfalls:
        lines += ["## Where softrod falls short of PyElastica (default variants)", "",
                  "Every error metric and the wall time (goal: a tenth of PyElastica's) "
                  "of softrod's default runs, against PyElastica's in the same run.", "",
                  *shortfalls]
    lines += [*sections]
    report.parent.mkdir(parents=True, exist_ok=True)
    report.write_text("\n".join(lines).rstrip() + "\n")


if __name__ == "__main__":
    main()
