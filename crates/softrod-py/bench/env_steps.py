"""Environment steps per second on softrod/Reach-v0 at 20 Hz control (a
benchmark, not a test; the numbers go to docs/performance.md, "Learning
environments").

    python crates/softrod-py/bench/env_steps.py [--steps 2000] [--envs 16]

Measures, with uniformly random actions and automatic resets:

- ``single``: one ``gymnasium.make("softrod/Reach-v0")`` env stepped in a
  Python loop (one core);
- ``batched, T thread(s)``: ``BatchedVectorEnv`` of ``--envs`` copies, its
  physics on T Rust threads (T = 1 and every core), counting every copy's
  step.

Each figure is the best of ``--repeats`` timed runs (contention on a
shared machine only ever adds time). Use a release install
(``bash scripts/install.sh``) for numbers worth recording.
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


def single(steps: int) -> float:
    env = gymnasium.make("softrod/Reach-v0")
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    actions = rng.uniform(0.0, se.DEFAULT_MAX_TENSION, (steps, env.action_space.shape[0]))
    t0 = time.perf_counter()
    for a in actions:
        _, _, terminated, truncated, _ = env.step(a)
        if terminated or truncated:
            env.reset()
    return steps / (time.perf_counter() - t0)


def batched(steps: int, n_envs: int, threads: int) -> float:
    venv = se.reach_vector_env(n_envs, threads=threads)
    venv.reset(seed=0)
    rng = np.random.default_rng(0)
    rounds = max(1, steps // n_envs)
    actions = rng.uniform(0.0, se.DEFAULT_MAX_TENSION, (rounds, n_envs, 2))
    t0 = time.perf_counter()
    for a in actions:
        venv.step(a)
    return rounds * n_envs / (time.perf_counter() - t0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=2000, help="env steps per timed run")
    ap.add_argument("--envs", type=int, default=16, help="copies of the batched env")
    ap.add_argument("--repeats", type=int, default=3, help="timed runs; the best is kept")
    args = ap.parse_args()
    cores = os.cpu_count() or 1
    print(
        f"softrod {softrod.__version__}, Python {platform.python_version()}, "
        f"{cores} cores, {platform.processor() or platform.machine()}"
    )
    print("softrod/Reach-v0, 20 Hz control (0.05 s per step), random actions\n")
    print("| configuration | env steps/s |\n|---|---|")
    best = max(single(args.steps) for _ in range(args.repeats))
    print(f"| single env, Python loop (1 core) | {best:,.0f} |")
    for threads in sorted({1, cores}):
        best = max(batched(args.steps, args.envs, threads) for _ in range(args.repeats))
        label = f"BatchedVectorEnv, {args.envs} copies, {threads} thread{'s' * (threads > 1)}"
        print(f"| {label} | {best:,.0f} |")


if __name__ == "__main__":
    main()
