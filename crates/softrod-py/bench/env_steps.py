"""Environment steps per second on softrod/Reach-v0 (or ``--env`` another
registered task) at 20 Hz control (a benchmark, not a test; the numbers go
to docs/performance.md, "Learning environments", and docs/envs.md).

    python crates/softrod-py/bench/env_steps.py [--env Reach-v0] [--steps 2000]
        [--envs 16] [--rtol R] [--substeps K] [--repeats 3]

Measures, with uniformly random actions and automatic resets:

- ``single``: one ``gymnasium.make("softrod/Reach-v0")`` env stepped in a
  Python loop (one core);
- ``batched, T thread(s)``: ``BatchedVectorEnv`` of ``--envs`` copies, its
  physics on T Rust threads (T = 1 and every core), counting every copy's
  step.

Each configuration prints two rates, each the best of ``--repeats`` timed
runs: env steps per second of wall-clock time, and env steps per second of
CPU time consumed by this process (all its threads: ``time.process_time``)
— per core, and much less disturbed than the wall clock when other work
shares the machine (contention adds waiting, not CPU time). ``--rtol`` and
``--substeps`` set the env's integration (default: the task's, rtol 1e-2).
Use a release install (``bash scripts/install.sh``) for numbers worth
recording.
"""

from __future__ import annotations

import argparse
import os
import platform
import time

import gymnasium
import numpy as np

import softrod
import softrod.envs as se


# The task measured (--env) and its batched vector env.
ENV = "Reach-v0"
VECTOR = {
    "Reach-v0": se.reach_vector_env,
    "Track-v0": se.track_vector_env,
    "ReachAround-v0": se.reach_around_vector_env,
    "Push-v0": se.push_vector_env,
}


def clocks():
    return time.perf_counter(), time.process_time()


def rates(steps: int, start) -> tuple[float, float]:
    wall, cpu = clocks()
    return steps / (wall - start[0]), steps / max(cpu - start[1], 1e-9)


def single(steps: int, kw: dict) -> tuple[float, float]:
    env = gymnasium.make(f"softrod/{ENV}", **kw)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(0.0, se.DEFAULT_MAX_TENSION, (steps, env.action_space.shape[0]))
    start = clocks()
    for a in actions:
        _, _, terminated, truncated, _ = env.step(a)
        if terminated or truncated:
            env.reset()
    return rates(steps, start)


def batched(steps: int, n_envs: int, threads: int, kw: dict) -> tuple[float, float]:
    venv = VECTOR[ENV](n_envs, threads=threads, **kw)
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    rounds = max(1, steps // n_envs)
    actions = rng.uniform(0.0, se.DEFAULT_MAX_TENSION, (rounds, n_envs, 2))
    start = clocks()
    for a in actions:
        venv.step(a)
    return rates(rounds * n_envs, start)


def best(runs: list[tuple[float, float]]) -> tuple[float, float]:
    return max(r[0] for r in runs), max(r[1] for r in runs)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--env", default="Reach-v0", choices=sorted(VECTOR), help="the task")
    ap.add_argument("--steps", type=int, default=2000, help="env steps per timed run")
    ap.add_argument("--envs", type=int, default=16, help="copies of the batched env")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs; the best is kept")
    ap.add_argument("--rtol", type=float, default=None, help="the env's rtol (default the task's)")
    ap.add_argument("--substeps", type=int, default=None, help="fixed steps per period")
    args = ap.parse_args()
    global ENV
    ENV = args.env
    kw = {}
    if args.rtol is not None:
        kw["rtol"] = args.rtol
    if args.substeps is not None:
        kw["substeps"] = args.substeps
    cores = os.cpu_count() or 1
    print(
        f"softrod {softrod.__version__}, Python {platform.python_version()}, "
        f"{cores} cores, {platform.processor() or platform.machine()}, "
        f"load average {os.getloadavg()[0]:.1f}"
    )
    env = gymnasium.make(f"softrod/{ENV}", **kw).unwrapped
    s = env.sim.settings
    print(
        f"softrod/{ENV}, 20 Hz control (0.05 s per step), random actions, "
        f"{s.integrator} rtol {s.rtol:g} atol {s.atol:g}, substeps {env.substeps}\n"
    )
    print("| configuration | env steps/s (wall) | env steps per CPU-second |\n|---|---|---|")
    w, c = best([single(args.steps, kw) for _ in range(args.repeats)])
    print(f"| single env, Python loop (1 core) | {w:,.0f} | {c:,.0f} |")
    for threads in sorted({1, cores}):
        w, c = best([batched(args.steps, args.envs, threads, kw) for _ in range(args.repeats)])
        label = f"BatchedVectorEnv, {args.envs} copies, {threads} thread{'s' * (threads > 1)}"
        print(f"| {label} | {w:,.0f} | {c:,.0f} |")
    print(f"\nload average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
