"""The 3-D release against PyElastica, whole process, at equal error (issue 30).

    python crates/softrod-py/bench/release3d_side_by_side.py --softrod target/release/softrod \
        [--rounds 2] [--elastica 32:5e-5,64:2.5e-5] [--softrod-settings 32:esdirk:1e-3,...]

Run it in an environment with softrod (`bash scripts/install.sh VENV`) and
`pip install pyelastica==1.0.0`. It prints a Markdown table with the date, the machine and
the versions (docs/performance.md, "Side by side with PyElastica").

The scene: a 0.5 m rubber rod (r = 1 cm, rho = 1000, E = 1e7, G = E/3), clamped at one end,
every strain free, undamped, released straight and horizontal under gravity, 0.3 s, the tip
sampled every 1 ms (301 samples). softrod: PCS with N pieces; PyElastica: its Cosserat rod
with n elements (`CosseratRod.straight_rod`, `OneEndFixedBC`, `GravityForces`, position
Verlet at a fixed dt, the tip position — its last node — sampled by a callback). PyElastica
scales its shear stiffness by alpha_c = 27/28; it is given G·28/27 so that both rods have
the shear stiffness G·A (softrod applies no correction factor).

The two simulators discretize space differently, so the error is measured against the
continuum: a converged reference (softrod with 128 pieces, esdirk rtol 1e-8) from which each
run's tip is at most `error` away over the 301 samples — space and time errors together.
PyElastica's finest run is printed against it too (the two rods' models agree to that).

"Whole process" as in release_side_by_side.py: a fresh process from the scene to the
written samples (softrod: `softrod run SCENE --out DIR`, every output file; PyElastica:
import, build, numba's first-call compilation, the run, the samples saved), timed from
outside, fastest of `--rounds` interleaved rounds.
"""

from __future__ import annotations

import argparse
import datetime
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

# The machine line of the planar script (this directory is on sys.path when run as a script).
from release_side_by_side import machine

DURATION, EVERY = 0.3, 1e-3
L, R, RHO, E = 0.5, 0.01, 1000.0, 1e7
G = E / 3.0
REFERENCE = (128, "esdirk", 1e-8)
ATOL_PER_RTOL = 1e-3

ELASTICA_WORKER = r"""
import sys
import numpy as np
import elastica as ea
n, dt, out = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
L, R, RHO, E, G, T, EVERY = (float(x) for x in sys.argv[4:11])
class Sim(ea.BaseSystemCollection, ea.Constraints, ea.Forcing, ea.CallBacks):
    pass
sim = Sim()
rod = ea.CosseratRod.straight_rod(n, np.zeros(3), np.array([1.0, 0.0, 0.0]),
                                  np.array([0.0, 0.0, 1.0]), L, R, RHO,
                                  youngs_modulus=E, shear_modulus=G * 28.0 / 27.0)
sim.append(rod)
sim.constrain(rod).using(ea.OneEndFixedBC, constrained_position_idx=(0,),
                         constrained_director_idx=(0,))
sim.add_forcing_to(rod).using(ea.GravityForces, acc_gravity=np.array([0.0, 0.0, -9.81]))
tips = []
class Tip(ea.CallBackBaseClass):
    def __init__(self, every):
        self.every = every
    def make_callback(self, system, time, current_step):
        if current_step % self.every == 0:
            tips.append(system.position_collection[:, -1].copy())
steps = int(round(T / dt))
every = int(round(EVERY / dt))
sim.collect_diagnostics(rod).using(Tip, every=every)
sim.finalize()
ea.integrate(ea.PositionVerlet(), sim, T, steps, progress_bar=False)
np.save(out, np.array(tips))
"""


def scene(pieces: int, integrator: str, rtol: float) -> str:
    return (f"[world]\ngravity = [0.0, 0.0, -9.81]\n\n[[rod]]\nname = \"arm\"\nlength = {L}\n"
            f"pieces = {pieces}\nstrains = \"all\"\n"
            f"section = {{ shape = \"circle\", radius = {R} }}\n"
            f"material = {{ density = {RHO}, young = {E}, poisson = 0.5 }}\n\n"
            f"[run]\nmode = \"dynamics\"\nduration = {DURATION}\nintegrator = \"{integrator}\"\n"
            f"rtol = {rtol:e}\natol = {ATOL_PER_RTOL * rtol:e}\noutput_every = {EVERY}\n")


def softrod_reference() -> np.ndarray:
    import softrod

    sim = softrod.Simulation.from_toml(scene(*REFERENCE))
    tr = sim.simulate(DURATION, output_every=EVERY)
    return tr.tip_position


def softrod_run(binary: str, path: Path, out: Path) -> tuple[float, np.ndarray]:
    start = time.perf_counter()
    subprocess.run([binary, "run", str(path), "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    d = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    return wall, np.column_stack([d["tip_x"], d["tip_y"], d["tip_z"]])


def elastica_run(n: int, dt: float, out: Path) -> tuple[float, np.ndarray | None]:
    start = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", ELASTICA_WORKER, str(n), repr(dt), str(out),
                        *(repr(x) for x in (L, R, RHO, E, G, DURATION, EVERY))],
                       capture_output=True, text=True)
    wall = time.perf_counter() - start
    if p.returncode != 0:
        print(f"pyelastica n={n} dt={dt} failed: {p.stderr[-500:]}", file=sys.stderr)
        return wall, None
    return wall, np.load(out)


def error(a: np.ndarray | None, b: np.ndarray) -> float:
    if a is None or a.shape != b.shape or not np.isfinite(a).all():
        return float("inf")
    return float(np.max(np.linalg.norm(a - b, axis=1)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--softrod", required=True, help="the softrod binary (release build)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--softrod-settings", default="32:esdirk:1e-2,32:esdirk:1e-3,32:esdirk:1e-4",
                    help="pieces:integrator:rtol triples")
    ap.add_argument("--elastica", default="32:5e-5,64:2.5e-5,128:1.25e-5",
                    help="elements:dt pairs; the last is also compared as the finest")
    args = ap.parse_args()
    settings = [(int(p), m, float(r)) for p, m, r in
                (x.split(":") for x in args.softrod_settings.split(","))]
    runs = [(int(n), float(dt)) for n, dt in (x.split(":") for x in args.elastica.split(","))]
    import softrod

    try:
        from importlib.metadata import version

        import elastica  # noqa: F401

        peer = f"pyelastica {version('pyelastica')}, numba {version('numba')}"
    except ImportError as e:
        peer, runs = None, []
        print(f"pyelastica not run: {e}", file=sys.stderr)
    header = (f"{datetime.date.today()}, {machine()}; softrod "
              f"{getattr(softrod, '__version__', '?')}" + (f", {peer}" if peer else ""))
    ref = softrod_reference()
    travel = float(np.max(np.linalg.norm(ref - ref[0], axis=1)))
    best: dict[tuple, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        paths = {}
        for s in settings:
            paths[s] = tmp / f"{s[0]}_{s[1]}_{s[2]:e}.toml"
            paths[s].write_text(scene(*s))
        for _ in range(args.rounds):
            for s in settings:
                wall, tip = softrod_run(args.softrod, paths[s], tmp / "out")
                row = best.setdefault(("softrod", s), [np.inf, error(tip, ref)])
                row[0] = min(row[0], wall)
            for r in runs:
                wall, tip = elastica_run(*r, tmp / "tips.npy")
                row = best.setdefault(("pyelastica", r), [np.inf, error(tip, ref)])
                row[0] = min(row[0], wall)
    print(f"3-D release side by side ({header}); fastest of {args.rounds} interleaved rounds; "
          f"tip travel {travel:.3f} m.")
    print()
    print("| simulator | setting | tip error vs continuum [m] | whole process [s] | "
          "fastest PyElastica at equal or better error / this |")
    print("|---|---|---|---|---|")
    for (who, s), v in best.items():
        if who == "softrod":
            peers = [w[0] for k, w in best.items() if k[0] == "pyelastica" and w[1] <= v[1]]
            ratio = f"{min(peers) / v[0]:.0f}×" if peers else "none as accurate"
            print(f"| softrod | {s[0]} pieces, {s[1]} rtol {s[2]:.0e} | {v[1]:.1e} | {v[0]:.3f} "
                  f"| {ratio} |")
        else:
            print(f"| pyelastica | {s[0]} elements, dt {s[1]:.2e} | {v[1]:.1e} | {v[0]:.2f} | – |")


if __name__ == "__main__":
    main()
