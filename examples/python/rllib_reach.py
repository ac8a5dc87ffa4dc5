"""Train RLlib's PPO on softrod/Reach-v0 for a few iterations (Ray RLlib
takes the env as any Gymnasium env).

    .venv/bin/pip install "ray[rllib]" torch     # RLlib's models need PyTorch (large)
    .venv/bin/python examples/python/rllib_reach.py [--iterations 3]

Not part of the tests: RLlib's algorithms need PyTorch, which the test
environment does not install. Run once on this machine (2026-12-06, ray
2.60.0 with PyTorch from PyPI, 2 CPUs shared with other sessions):
iterations of 400 env steps in 1.4–3.0 s.
"""

from __future__ import annotations

import argparse
import sys
import time

try:
    import ray
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env
except ImportError as e:  # extras: say so in one line instead of a traceback
    sys.exit(f"rllib_reach.py needs ray[rllib] and torch ({e.name} is missing): "
             'pip install "ray[rllib]" torch')


def make_env(config):
    # Imported in the worker: the env runners are other processes.
    import softrod.envs

    return softrod.envs.reach_env(**config)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--iterations", type=int, default=3)
    args = ap.parse_args()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    register_env("softrod-reach", make_env)
    config = (
        PPOConfig()
        .environment("softrod-reach")
        .env_runners(num_env_runners=1, num_envs_per_env_runner=2)
        .training(train_batch_size_per_learner=400, minibatch_size=100, num_epochs=2)
    )
    algo = config.build_algo()
    for i in range(args.iterations):
        t0 = time.perf_counter()
        result = algo.train()
        runners = result.get("env_runners", {})
        print(f"iteration {i + 1}: {time.perf_counter() - t0:.1f} s, "
              f"{runners.get('num_env_steps_sampled_lifetime')} env steps, "
              f"mean episode return {runners.get('episode_return_mean')}")
    algo.stop()
    ray.shutdown()


if __name__ == "__main__":
    main()
