"""Whole-process cost of the planar release against soromox, side by side (issue 30).

    python crates/softrod-py/bench/release_side_by_side.py --softrod target/release/softrod \
        [--rounds 2] [--soromox-dt 1e-4,5e-5] [--softrod-settings esdirk:1e-3,esdirk:1e-5,...]

Run it in an environment with softrod (release build: `bash scripts/install.sh VENV`) and,
for the peer, `pip install soromox==0.5.0` (JAX from PyPI, CPU); without soromox only
softrod's rows are printed. It prints a Markdown table with the date, the machine and the
versions (docs/performance.md, "Side by side with soromox").

The scene is `examples/cantilever_gravity.toml`: a 0.5 m rubber rod (r = 1 cm,
rho = 1000, E = 1e7, G = E/3), 8 pieces, bending, stretch and shear in the plane,
undamped, released straight under gravity, 1 s, output every 1 ms. soromox's model of it
is `PlanarPCS` with 8 links of the same length, radius, density and moduli, base pose
`[0, 0, 0]` (the rod along x, gravity along -y: softrod's z is soromox's y), integrated by
diffrax's Tsit5 at a fixed step (soromox's default; it diverges at dt >= 1.25e-4).

"Whole process" is what a user waits for: a fresh process that reads the scene, builds the
model, integrates and writes its outputs (softrod: `softrod run SCENE --out DIR`, every
output file; soromox: import, build, jit-compile and run the rollout, saving the 1 001 tip
positions) — timed from outside, the fastest of `--rounds` rounds, the configurations
interleaved within each round so that they see the same machine load. The soromox worker
then calls the compiled rollout a second time, which is reported beside (and subtracted
from the process's wall time).

Tip error: the largest distance over the 1 001 output times between the tip and a converged
reference of the *same* simulator (softrod: radau5 at rtol 1e-10; soromox: Tsit5 at dt
2.5e-5, five-th order: (2.5e-5/1e-4)^5 = 1e-3 of the default's error), i.e. the time
integration error each run makes on its own model. The two references' distance (the two
models' difference, quadrature and shear conventions) is printed beside them.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "examples" / "cantilever_gravity.toml"
DURATION, EVERY = 1.0, 1e-3
SOROMOX_REFERENCE_DT = 2.5e-5
# The scene's ratio (atol 1e-6 at rtol 1e-3), kept as rtol tightens: a fixed atol would
# cap the accuracy (radau5 at rtol 1e-8 with atol 1e-6 was 2e-6 m off, worse than at 1e-6).
ATOL_PER_RTOL = 1e-3

SOROMOX_WORKER = r"""
import sys, time
t0 = time.perf_counter()
import numpy as np, jax, jax.numpy as jnp
jax.config.update("jax_enable_x64", True)
import diffrax
from soromox.systems.components import LinkSpec
from soromox.systems.pcs.planar_pcs import PlanarPCS
from soromox.systems.system_state import SystemState
dt, out = float(sys.argv[1]), sys.argv[2]
links = [LinkSpec.circular(length=0.5 / 8, radius=0.01, density=1000.0,
                           reference_strain=[0.0, 1.0, 0.0], young_modulus=1e7,
                           shear_modulus=1e7 / 3) for _ in range(8)]
robot = PlanarPCS.from_links(links, gravity=jnp.array([0.0, -9.81]),
                             base_pose=jnp.array([0.0, 0.0, 0.0]))
n = robot.num_internal_dofs
ts = jnp.linspace(0.0, 1.0, 1001)
state = SystemState(t=0.0, y=jnp.zeros(2 * n))
def roll():
    r = robot.rollout_to(state, t1=1.0, solver_dt=dt, save_ts=ts, solver=diffrax.Tsit5(),
                         max_steps=None)
    tips = jax.vmap(lambda y: robot.forward_kinematics_tips(y[:n])[-1])(r.y)
    return np.asarray(tips.block_until_ready())
t1 = time.perf_counter()
tips = roll()
t2 = time.perf_counter()
roll()
t3 = time.perf_counter()
np.save(out, tips[:, 1:3])  # chi = [theta, x, y]
print(f"{t2 - t1} {t3 - t2} {t1 - t0}")
"""


def machine() -> str:
    cpu = "unknown CPU"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return f"{platform.machine()}, {os.cpu_count()} CPUs ({cpu}), load average {load:.1f} at start"


def softrod_reference() -> np.ndarray:
    import softrod

    sim = softrod.Simulation.from_file(str(SCENE))
    tr = sim.simulate(DURATION, integrator="radau5", rtol=1e-10, atol=1e-13,
                      output_every=EVERY)
    return tr.tip_position[:, [0, 2]]


def scene_with(integrator: str, rtol: float) -> str:
    text = SCENE.read_text()
    text = re.sub(r"(?m)^rtol = .*$", f"rtol = {rtol:e}", text)
    text = re.sub(r"(?m)^atol = .*$", f"atol = {ATOL_PER_RTOL * rtol:e}", text)
    text = re.sub(r"(?m)^integrator = .*$", f'integrator = "{integrator}"', text)
    return text


def softrod_run(binary: str, scene: Path, out: Path) -> tuple[float, np.ndarray]:
    start = time.perf_counter()
    subprocess.run([binary, "run", str(scene), "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    wall = time.perf_counter() - start
    data = np.genfromtxt(out / "trajectory.csv", delimiter=",", names=True)
    return wall, np.column_stack([data["tip_x"], data["tip_z"]])


def soromox_run(dt: float, out: Path) -> tuple[float, float, float, np.ndarray]:
    start = time.perf_counter()
    p = subprocess.run([sys.executable, "-c", SOROMOX_WORKER, repr(dt), str(out)], check=True,
                       capture_output=True, text=True)
    wall = time.perf_counter() - start
    first, second, _imports = (float(x) for x in p.stdout.split()[-3:])
    return wall - second, first, second, np.load(out)


def error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.hypot(*(a - b).T)))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--softrod", required=True, help="the softrod binary (release build)")
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--softrod-settings",
                    default="esdirk:1e-3,esdirk:1e-4,esdirk:1e-5,radau5:1e-6,radau5:1e-8",
                    help="integrator:rtol pairs (atol = 1e-3 rtol, the scene's ratio)")
    ap.add_argument("--soromox-dt", default="1e-4,5e-5")
    args = ap.parse_args()
    settings = [(x.split(":")[0], float(x.split(":")[1])) for x in args.softrod_settings.split(",")]
    dts = [float(x) for x in args.soromox_dt.split(",")]
    import softrod

    try:
        import jax  # noqa: F401
        import soromox

        peer = f"soromox {soromox.__version__}, jax {jax.__version__} (CPU, x64)"
    except ImportError as e:
        peer, dts = None, []
        print(f"soromox not run: {e}", file=sys.stderr)

    header = (f"{datetime.date.today()}, {machine()}; softrod "
              f"{getattr(softrod, '__version__', '?')}" + (f", {peer}" if peer else ""))
    ref = softrod_reference()
    best: dict[tuple, list] = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        scenes = {}
        for m, r in settings:
            scenes[m, r] = tmp / f"{m}_{r:e}.toml"
            scenes[m, r].write_text(scene_with(m, r))
        sorox_ref = None
        if dts:
            _, _, _, sorox_ref = soromox_run(SOROMOX_REFERENCE_DT, tmp / "sorox_ref.npy")
        for _ in range(args.rounds):
            for m, r in settings:
                wall, tip = softrod_run(args.softrod, scenes[m, r], tmp / "out")
                row = best.setdefault(("softrod", (m, r)), [np.inf, error(tip, ref)])
                row[0] = min(row[0], wall)
            for dt in dts:
                wall, first, second, tip = soromox_run(dt, tmp / "sorox.npy")
                row = best.setdefault(("soromox", dt), [np.inf, np.inf, np.inf,
                                                        error(tip, sorox_ref)])
                row[0], row[1], row[2] = min(row[0], wall), min(row[1], first), min(row[2], second)
    fastest_peer = min((v[0] for k, v in best.items() if k[0] == "soromox"), default=None)
    print(f"Planar release side by side ({header}); fastest of {args.rounds} interleaved rounds.")
    print()
    print("| simulator | setting | tip error [m] | whole process [s] | compile + run / run [s] | "
          "soromox's fastest / this |")
    print("|---|---|---|---|---|---|")
    for (who, setting), v in best.items():
        if who == "softrod":
            ratio = f"{fastest_peer / v[0]:.0f}×" if fastest_peer else "–"
            print(f"| softrod | {setting[0]} rtol {setting[1]:.0e} | {v[1]:.1e} | {v[0]:.3f} | – "
                  f"| {ratio} |")
        else:
            print(f"| soromox | Tsit5 dt {setting:.1e} | {v[3]:.1e} | {v[0]:.2f} | "
                  f"{v[1]:.2f} / {v[2]:.2f} | – |")
    if sorox_ref is not None:
        print()
        print(f"Distance between the two references (the models' difference): "
              f"{error(ref, sorox_ref):.1e} m over a tip travel of "
              f"{float(np.max(np.hypot(*(ref - ref[0]).T))):.3f} m.")


if __name__ == "__main__":
    main()
