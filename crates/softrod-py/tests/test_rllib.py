"""RLlib with the softrod envs: an RLlib algorithm config built with
softrod/Reach-v0 and softrod/Push-v0 and one training iteration on the
local Ray cluster of the session (conftest.ray_cluster, num_cpus=2).

RLlib's algorithms need PyTorch, which the test environment does not
install (PyPI's Linux torch brings ~3 GB of CUDA libraries, and the issue
keeps PyTorch out of the test environment), so these tests are skipped —
with the reason in pytest's summary (``-rs``) — unless ``ray.rllib`` and
``torch`` import. To run them (crates/softrod-py/requirements-rllib.txt):

    SOFTROD_TEST_RLLIB=1 bash scripts/install.sh --dev
    SOFTROD_BIN=target/debug/softrod .venv/bin/python -m pytest -rs \\
        crates/softrod-py/tests/test_rllib.py
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("gymnasium")
pytest.importorskip("ray.rllib", reason="ray[rllib] is not installed (pip install 'ray[rllib]')")
pytest.importorskip("torch", reason="PyTorch is not installed: RLlib's algorithms need it")


def make_env(config):
    # Runs in RLlib's env-runner processes: the import registers the envs
    # there too.
    import softrod.envs

    return softrod.envs.make_env_from_config(config)


@pytest.mark.parametrize("task", ["reach", "push"])
def test_one_ppo_training_iteration(ray_cluster, task):
    from ray.rllib.algorithms.ppo import PPOConfig
    from ray.tune.registry import register_env

    register_env("softrod-rllib", make_env)
    config = (
        PPOConfig()
        .environment("softrod-rllib", env_config={"task": task, "episode_steps": 20})
        .env_runners(num_env_runners=1, num_envs_per_env_runner=2)
        .training(train_batch_size_per_learner=80, minibatch_size=40, num_epochs=1)
        .debugging(seed=0)
    )
    algo = config.build_algo()
    try:
        result = algo.train()
    finally:
        algo.stop()
    runners = result["env_runners"]
    assert runners["num_env_steps_sampled_lifetime"] >= 80
    # Episodes of 20 steps completed, with finite returns (rewards are
    # negative distances: never NaN, at most 0).
    ret = runners["episode_return_mean"]
    assert math.isfinite(ret) and ret <= 0.0
    assert np.isfinite(result["learners"]["default_policy"]["total_loss"])
