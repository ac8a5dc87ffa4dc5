"""Cost of one forward-dynamics call from Python against the same call in Rust.

    python crates/softrod-py/bench/forward_dynamics.py [--rounds 7] [--calls 20000]

Run it in an environment with a *release* build of softrod that has the
test hooks (`maturin develop --release --features test-hooks
--manifest-path crates/softrod-py/Cargo.toml` in the environment); soromox (PyPI, with JAX) is timed beside
it on the planar scene when it imports. Numbers go in docs/performance.md,
section "Python".

Scenes:
- "N = 10, all strains": the criterion bench `forward_dynamics/10`
  (benches/benches/dynamics.rs): L = 0.5 m, r = 1 cm, rho = 1000, E = 1e7,
  G = E/3, mu = 1 Pa s, gravity, 4 Gauss points, 60 coordinates, at the
  bench's seeded state (SplitMix64, seed 42, ported below).
- "planar, N = 10": the same rod with strains kz, qx, qy (30 coordinates),
  undamped, gravity along -y, and soromox's PlanarPCS with 10 links of the
  same length, radius, density and moduli (jax.jit, x64, CPU).

Each round times the Rust loop (`softrod._softrod._time_forward_dynamics`:
the facade's `Simulation::forward_dynamics` called `calls` times from Rust)
and then the Python loop (`sim.forward_dynamics(0.0, q, qd)` with float64
arrays) back to back, so both see the same machine load; the table reports
the fastest round of each.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import softrod
from softrod import _softrod


def splitmix(seed: int):
    """The benches' SplitMix64 in [-1, 1)."""
    state = seed
    mask = (1 << 64) - 1
    while True:
        state = (state + 0x9E3779B97F4A7C15) & mask
        z = state
        z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & mask
        z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & mask
        z ^= z >> 31
        yield (z >> 11) / float(1 << 52) - 1.0


def bench_state(n_dof: int, seed: int = 42):
    rng = splitmix(seed)
    q = np.array([(2.0 if i % 6 < 3 else 0.02) * next(rng) for i in range(n_dof)])
    qd = np.array([next(rng) for _ in range(n_dof)])
    return q, qd


def rod(strains, viscosity):
    return softrod.Rod(length=0.5, pieces=10, strains=strains, section=softrod.Circle(0.01),
                       material=softrod.Material(density=1000.0, young=1e7,
                                                 shear_modulus=1e7 / 3, viscosity=viscosity))


def python_loop(sim, q, qd, calls):
    f = sim.forward_dynamics
    start = time.perf_counter()
    for _ in range(calls):
        f(0.0, q, qd)
    return (time.perf_counter() - start) / calls


def soromox_call():
    """A jitted soromox PlanarPCS forward dynamics of the planar scene, or None."""
    try:
        import jax
        import jax.numpy as jnp

        jax.config.update("jax_enable_x64", True)
        from soromox.systems.components import LinkSpec
        from soromox.systems.pcs.planar_pcs import PlanarPCS
    except Exception as error:  # noqa: BLE001 - report why it is missing
        print(f"soromox not timed: {error}")
        return None, None
    import soromox

    links = [LinkSpec.circular(length=0.05, radius=0.01, density=1000.0,
                               reference_strain=[0.0, 1.0, 0.0], young_modulus=1e7,
                               shear_modulus=1e7 / 3) for _ in range(10)]
    robot = PlanarPCS.from_links(links, gravity=jnp.array([0.0, -9.81]))
    n = robot.num_internal_dofs
    q, qd = bench_state(n, seed=7)
    y = jnp.concatenate([jnp.asarray(q), jnp.asarray(qd)])
    f = jax.jit(lambda t, y: robot.forward_dynamics(t, y))
    f(0.0, y).block_until_ready()  # compile

    def call(calls):
        start = time.perf_counter()
        for _ in range(calls):
            f(0.0, y).block_until_ready()
        return (time.perf_counter() - start) / calls

    return call, f"soromox {soromox.__version__}, jax {jax.__version__} ({jax.default_backend()})"


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=7)
    parser.add_argument("--calls", type=int, default=20000)
    args = parser.parse_args()

    full = softrod.Simulation(rods=[rod("all", 1.0)], gravity=[0, 0, -9.81])
    planar = softrod.Simulation(rods=[rod(["kz", "qx", "qy"], 0.0)], gravity=[0, -9.81, 0])
    scenes = {"N = 10, all strains (60 dof)": (full, *bench_state(full.n_dof)),
              "planar, N = 10 (30 dof)": (planar, *bench_state(planar.n_dof, seed=7))}
    sorox, sorox_name = soromox_call()
    best = {name: [np.inf, np.inf] for name in scenes}
    best_sorox = np.inf
    for _ in range(args.rounds):
        for name, (sim, q, qd) in scenes.items():
            r = _softrod._time_forward_dynamics(sim, q.tolist(), qd.tolist(), args.calls)
            p = python_loop(sim, q, qd, args.calls)
            best[name] = [min(best[name][0], r), min(best[name][1], p)]
        if sorox is not None:
            best_sorox = min(best_sorox, sorox(max(args.calls // 20, 100)))
    print(f"fastest of {args.rounds} rounds of {args.calls} calls, softrod {softrod.__version__}\n")
    print("| scene | Rust loop | Python call | Python / Rust | overhead |")
    print("|---|---|---|---|---|")
    for name, (r, p) in best.items():
        print(f"| {name} | {r * 1e6:.2f} µs | {p * 1e6:.2f} µs | {p / r:.2f} | "
              f"{(p - r) * 1e6:.2f} µs |")
    if sorox is not None:
        print(f"| planar, N = 10, {sorox_name} | – | {best_sorox * 1e6:.1f} µs | – | – |")


if __name__ == "__main__":
    main()
