"""Gradient of a whole trajectory against soromox's jax.grad through diffrax (issue 28).

    python crates/softrod-py/bench/gradient_side_by_side.py [--duration 1.0] [--samples 20]
        [--rounds 2] [--soromox-dt 1e-4]

Run it in an environment with softrod (release build: `bash scripts/install.sh VENV`) and,
for the peer, `pip install soromox==0.5.0` (JAX from PyPI, CPU); without soromox only
softrod's rows are printed. It prints Markdown tables with the date, the machine and the
versions (docs/performance.md, "Trajectory gradients", side by side with soromox).

The model is the planar release of `examples/cantilever_gravity.toml` (a 0.5 m rubber rod,
r = 1 cm, rho = 1000, E = 1e7, nu = 0.5 so G = E/3, 8 pieces with bending, stretch and shear
in the plane, clamped, released straight under gravity), soromox's `PlanarPCS` of the same
rod as in `release_side_by_side.py` (softrod's z is soromox's y). The loss is the same on
both sides: L = sum_k 1/2 |tip(t_k) - c|^2 over t_k = k T / K, k = 1..K, with the fixed
point c = (0.25, -0.25) m in the plane (softrod's `{"type": "position"}` loss with weight 1).

The parameters are the two material scales: s_E multiplies Young's and the shear modulus
(softrod: `ROD.young`, whose shear modulus follows it at the scene's fixed Poisson ratio;
dL/ds_E = E dL/dE), s_rho the density (dL/ds_rho = rho dL/drho). soromox builds its model
from Python floats (its link validation cannot be traced), so its parameters are applied
by scaling the built model's stiffness and mass fields (`equinox.tree_at`); the worker
checks that scaling against central differences of models rebuilt at E(1 +- h), rho(1 +- h)
and prints the check. With gravity the only load and no damping, the motion depends on
rho/E alone, so the two derivatives are equal and opposite (a check on both sides).

Timing, each side's best of `--rounds`: softrod's plain forward run (`simulate` at the same
sample times) and `value_and_gradient` (the discrete adjoint of its ESDIRK), at the scene's
settings (rtol 1e-3) and at rtol 1e-4 and 1e-6; soromox's forward rollout (`jax.jit`) and
`jax.jit(jax.value_and_grad(...))` through diffrax's Tsit5 at its fixed step (its default
adjoint, `RecursiveCheckpointAdjoint`), the first call (trace + compile + run) and a second
call (run alone) reported apart. Each side's gradient is compared with softrod's at rtol
1e-9 (the models' difference shows there: the two references differ by ~1e-7 relative in
the tip, release_side_by_side.py).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
SCENE = ROOT / "examples" / "cantilever_gravity.toml"
TARGET = (0.25, -0.25)  # (x, z) in softrod's frame = (x, y) in soromox's
E0, RHO0 = 1e7, 1000.0

SOROMOX_WORKER = r"""
import json, sys, time
t_import = time.perf_counter()
import numpy as np, jax, jax.numpy as jnp, equinox as eqx
jax.config.update("jax_enable_x64", True)
import diffrax
from soromox.systems.components import LinkSpec
from soromox.systems.pcs.planar_pcs import PlanarPCS
from soromox.systems.system_state import SystemState
T, K, dt, cx, cy, E0, RHO0 = (float(a) for a in sys.argv[1:8])
K = int(K)
def build(E, rho):
    links = [LinkSpec.circular(length=0.5 / 8, radius=0.01, density=rho,
                               reference_strain=[0.0, 1.0, 0.0], young_modulus=E,
                               shear_modulus=E / 3) for _ in range(8)]
    return PlanarPCS.from_links(links, gravity=jnp.array([0.0, -9.81]),
                                base_pose=jnp.array([0.0, 0.0, 0.0]))
base = build(E0, RHO0)
STIFF = lambda r: (r.params.link.stiffness, r.K_full, r.K_active,
                   r.young_stiffness_operator, r.shear_stiffness_operator)
MASS = lambda r: (r.params.link.density, r.rho, r.M_segments, r.weighted_mass_diagonals)
def scaled(p):
    r = eqx.tree_at(STIFF, base, tuple(x * p[0] for x in STIFF(base)))
    return eqx.tree_at(MASS, r, tuple(x * p[1] for x in MASS(r)))
ts = jnp.linspace(0.0, T, K + 1)
c = jnp.array([cx, cy])
def loss_robot(robot):
    n = robot.num_internal_dofs
    st = SystemState(t=0.0, y=jnp.zeros(2 * n))
    r = robot.rollout_to(st, t1=T, solver_dt=dt, save_ts=ts, solver=diffrax.Tsit5(),
                         max_steps=int(round(T / dt)) + 16)
    tips = jax.vmap(lambda y: robot.forward_kinematics_tips(y[:n])[-1])(r.y)
    d = tips[1:, 1:3] - c  # chi = [theta, x, y]
    return 0.5 * jnp.sum(d * d)
p0 = jnp.array([1.0, 1.0])
fwd = jax.jit(lambda p: loss_robot(scaled(p)))
vg = jax.jit(jax.value_and_grad(lambda p: loss_robot(scaled(p))))
out = {"import_s": time.perf_counter() - t_import}
t = time.perf_counter(); v = float(fwd(p0)); out["forward_first_s"] = time.perf_counter() - t
t = time.perf_counter(); v = float(fwd(p0)); out["forward_s"] = time.perf_counter() - t
t = time.perf_counter(); val, g = vg(p0); g = np.asarray(g); out["grad_first_s"] = time.perf_counter() - t
t = time.perf_counter(); val, g = vg(p0); g = np.asarray(g); out["grad_s"] = time.perf_counter() - t
out["value"] = float(val); out["grad"] = [float(x) for x in g]
rebuilt = eqx.filter_jit(loss_robot)
h = 1e-4
out["fd_rebuilt"] = [
    float((rebuilt(build(E0 * (1 + h), RHO0)) - rebuilt(build(E0 * (1 - h), RHO0))) / (2 * h)),
    float((rebuilt(build(E0, RHO0 * (1 + h))) - rebuilt(build(E0, RHO0 * (1 - h)))) / (2 * h)),
]
out["versions"] = {"jax": jax.__version__}
try:
    from importlib.metadata import version
    out["versions"]["soromox"] = version("soromox"); out["versions"]["diffrax"] = version("diffrax")
except Exception:
    pass
print(json.dumps(out))
"""


def softrod_side(duration: float, samples: int, rtol: float, rounds: int) -> dict:
    import softrod

    sim = softrod.Simulation.from_file(SCENE)
    sim.settings = sim.settings.replace(rtol=rtol, atol=1e-3 * rtol)
    rod = sim.rod_names[0]
    length = sim.rod_lengths[0]
    times = [duration * k / samples for k in range(1, samples + 1)]
    loss = {
        "type": "position",
        "rod": rod,
        "s": length,
        "times": times,
        "targets": [[TARGET[0], 0.0, TARGET[1]]] * samples,
        "weight": 1.0,
    }
    params = [f"{rod}.young", f"{rod}.density"]
    best = {"forward_s": np.inf, "grad_s": np.inf}
    for _ in range(rounds):
        t = time.perf_counter()
        sim.simulate(duration, output_every=duration / samples)
        best["forward_s"] = min(best["forward_s"], time.perf_counter() - t)
        t = time.perf_counter()
        value, grad = sim.value_and_gradient(loss, params, duration)
        best["grad_s"] = min(best["grad_s"], time.perf_counter() - t)
    best["value"] = value
    best["grad"] = [E0 * float(grad[params[0]]), RHO0 * float(grad[params[1]])]
    return best


def soromox_side(duration: float, samples: int, dt: float) -> dict | None:
    try:
        import soromox  # noqa: F401
    except ImportError:
        return None
    args = [duration, samples, dt, TARGET[0], TARGET[1], E0, RHO0]
    t = time.perf_counter()
    p = subprocess.run(
        [sys.executable, "-c", SOROMOX_WORKER, *map(str, args)],
        capture_output=True,
        text=True,
        env={**os.environ, "JAX_PLATFORMS": "cpu"},
    )
    wall = time.perf_counter() - t
    if p.returncode != 0:
        raise SystemExit(f"soromox worker failed:\n{p.stderr[-3000:]}")
    out = json.loads(p.stdout.strip().splitlines()[-1])
    out["process_s"] = wall
    return out


def rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)) / np.abs(np.asarray(b))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--samples", type=int, default=20)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--soromox-dt", type=float, default=1e-4)
    a = ap.parse_args()

    import softrod

    ref = softrod_side(a.duration, a.samples, 1e-9, 1)
    rows = [("softrod", f"esdirk rtol {r:g}", softrod_side(a.duration, a.samples, r, a.rounds))
            for r in (1e-3, 1e-4, 1e-6)]
    soro = soromox_side(a.duration, a.samples, a.soromox_dt)

    print(f"{datetime.date.today()}, {platform.machine()} {platform.processor() or ''} "
          f"({os.cpu_count()} CPUs), Python {platform.python_version()}, "
          f"softrod {softrod.__version__}"
          + (f", soromox {soro['versions'].get('soromox')}, jax {soro['versions']['jax']}, "
             f"diffrax {soro['versions'].get('diffrax')}" if soro else ""))
    print(f"\nplanar release, T = {a.duration} s, loss at {a.samples} times; "
          f"reference dL/ds_E = {ref['grad'][0]:.6e}, dL/ds_rho = {ref['grad'][1]:.6e} "
          f"(softrod rtol 1e-9), L = {ref['value']:.6e}\n")
    print("| simulator | setting | L | dL/ds_E | dL/ds_rho | gradient rel. error "
          "| forward run [s] | gradient [s] | gradient / forward |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, setting, r in rows:
        print(f"| {name} | {setting} | {r['value']:.6e} | {r['grad'][0]:.6e} | "
              f"{r['grad'][1]:.6e} | {rel(r['grad'], ref['grad']):.1e} | {r['forward_s']:.4f} | "
              f"{r['grad_s']:.4f} | {r['grad_s'] / r['forward_s']:.1f} |")
    if soro:
        print(f"| soromox | Tsit5 dt {a.soromox_dt:g}, jax.grad | {soro['value']:.6e} | "
              f"{soro['grad'][0]:.6e} | {soro['grad'][1]:.6e} | "
              f"{rel(soro['grad'], ref['grad']):.1e} | {soro['forward_s']:.3f} "
              f"(first call {soro['forward_first_s']:.2f}) | {soro['grad_s']:.3f} "
              f"(first call {soro['grad_first_s']:.2f}) | "
              f"{soro['grad_s'] / soro['forward_s']:.1f} |")
        print(f"\nsoromox's gradient by scaling the built model against central differences "
              f"of rebuilt models: {soro['grad']} vs {soro['fd_rebuilt']} "
              f"(rel. {rel(soro['grad'], soro['fd_rebuilt']):.1e}); its process "
              f"{soro['process_s']:.1f} s (import {soro['import_s']:.1f} s)")
        best = rows[0][2]
        print(f"\nsoromox's gradient (run alone) / softrod's at rtol 1e-3: "
              f"{soro['grad_s'] / best['grad_s']:.0f}x; first call / softrod: "
              f"{soro['grad_first_s'] / best['grad_s']:.0f}x")


if __name__ == "__main__":
    main()
