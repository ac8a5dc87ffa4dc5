"""Train PPO (Stable-Baselines3) on softrod/Reach-v0 and plot its learning
curve.

    .venv/bin/pip install stable-baselines3 matplotlib    # PyTorch comes with it (large)
    .venv/bin/python examples/python/train_reach_ppo.py [--steps 200000] [--envs 8]
        [--vec batched|dummy] [--out DIR]

Not part of the tests (Stable-Baselines3 and PyTorch are kept out of the
test environment). The reach task: a 0.3 m two-cable soft arm, 20 Hz
control, 100 steps (5 s) per episode, a random reachable target per episode
(docs/envs.md). The actions are rescaled to [-1, 1] (what PPO's Gaussian
policy expects) and the observations normalized by running statistics
(VecNormalize). At the end the script evaluates the deterministic policy on
100 fresh episodes and prints the success rate (final tip within 5 % of the
arm's length of the target) and the mean final distance beside those of
the zero action, and writes DIR/train_reach_ppo.png (default out/python/):
episode return against environment steps.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

try:
    import gymnasium
    from stable_baselines3 import PPO
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.vec_env import VecEnv, VecMonitor, VecNormalize
except ImportError as e:  # extras: say so in one line instead of a traceback
    sys.exit(f"train_reach_ppo.py needs gymnasium and stable-baselines3 ({e.name} is missing): "
             "pip install softrod[rl] stable-baselines3 matplotlib")

import softrod.envs  # registers softrod/Reach-v0


def make_env():
    env = gymnasium.make("softrod/Reach-v0")
    return gymnasium.wrappers.RescaleAction(env, -1.0, 1.0)


def _row(info: dict, i: int) -> dict:
    """Copy i's entries of a Gymnasium vector info (arrays with "_key"
    masks, nested dicts for dict values)."""
    return {
        k: _row(v, i) if isinstance(v, dict) else v[i]
        for k, v in info.items()
        if not k.startswith("_") and info["_" + k][i]
    }


class BatchedVecEnv(VecEnv):
    """Stable-Baselines3's VecEnv over softrod's BatchedVectorEnv: the
    copies' physics steps in one call on Rust threads. SB3 resets a copy in
    the step that ends its episode (Gymnasium's SAME_STEP autoreset, whose
    final observation SB3 calls "terminal_observation"); actions in [-1, 1]
    are mapped to tensions in [0, max_tension]."""

    def __init__(self, n_envs: int, seed: int):
        from gymnasium.vector import AutoresetMode

        self.venv = softrod.envs.reach_vector_env(n_envs, autoreset_mode=AutoresetMode.SAME_STEP)
        self.high = self.venv.single_action_space.high
        box = gymnasium.spaces.Box(-1.0, 1.0, self.high.shape, dtype=np.float32)
        super().__init__(n_envs, self.venv.single_observation_space, box)
        self._seed = seed

    def reset(self):
        obs, _ = self.venv.reset(seed=self._seed)
        self._seed += self.num_envs
        return obs

    def step_async(self, actions):
        self._actions = (np.clip(actions, -1.0, 1.0) + 1.0) * 0.5 * self.high

    def step_wait(self):
        obs, rewards, terminated, truncated, info = self.venv.step(self._actions)
        infos = [_row(info, i) for i in range(self.num_envs)]
        for i, d in enumerate(infos):
            if "final_obs" in d:
                d["terminal_observation"] = d.pop("final_obs")
                d.update(d.pop("final_info"))
            d["TimeLimit.truncated"] = bool(truncated[i] and not terminated[i])
        return obs, rewards.astype(np.float32), terminated | truncated, infos

    def close(self):
        self.venv.close()

    def get_attr(self, attr_name, indices=None):
        return [getattr(e, attr_name) for e in self._envs(indices)]

    def set_attr(self, attr_name, value, indices=None):
        for e in self._envs(indices):
            setattr(e, attr_name, value)

    def env_method(self, method_name, *args, indices=None, **kwargs):
        return [getattr(e, method_name)(*args, **kwargs) for e in self._envs(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None):
        return [False for _ in self._envs(indices)]

    def _envs(self, indices):
        envs = self.venv.envs
        if indices is None:
            return envs
        return [envs[i] for i in ([indices] if isinstance(indices, int) else indices)]


def evaluate(model, vec_norm: VecNormalize | None, episodes: int, seed: int,
             zero: bool = False) -> tuple[float, float]:
    """Success rate and mean final distance [m] over `episodes` episodes."""
    env = make_env()
    successes, distances = 0, []
    for k in range(episodes):
        obs, info = env.reset(seed=seed + k)
        done = False
        while not done:
            if zero:
                action = -np.ones(env.action_space.shape)  # -1 = zero tension
            else:
                o = vec_norm.normalize_obs(obs) if vec_norm is not None else obs
                action, _ = model.predict(o, deterministic=True)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
        successes += bool(info["is_success"])
        distances.append(info["distance"])
    return successes / episodes, float(np.mean(distances))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=200_000, help="environment steps of training")
    ap.add_argument("--envs", type=int, default=8, help="parallel copies of the env")
    ap.add_argument("--vec", choices=["batched", "dummy"], default="batched",
                    help="batched: softrod's BatchedVectorEnv (Rust threads); "
                         "dummy: SB3's DummyVecEnv of single envs")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("out/python"))
    args = ap.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    for old in args.out.glob("*monitor.csv"):
        old.unlink()

    if args.vec == "batched":
        venv = VecMonitor(BatchedVecEnv(args.envs, args.seed),
                          filename=str(args.out / "reach_ppo"))
    else:
        venv = make_vec_env(make_env, n_envs=args.envs, seed=args.seed,
                            monitor_dir=str(args.out))
    venv = VecNormalize(venv, norm_obs=True, norm_reward=True, gamma=0.99)
    model = PPO("MlpPolicy", venv, n_steps=256, batch_size=256, learning_rate=3e-4,
                gamma=0.99, seed=args.seed, verbose=0)
    t0 = time.perf_counter()
    model.learn(total_timesteps=args.steps)
    wall = time.perf_counter() - t0
    venv.training = False

    rate, dist = evaluate(model, venv, 100, seed=10_000)
    rate0, dist0 = evaluate(model, None, 100, seed=10_000, zero=True)
    print(f"trained {args.steps} steps in {wall:.0f} s ({args.steps / wall:.0f} steps/s, "
          f"{args.envs} envs, {args.vec})")
    print(f"PPO:          success {rate:.0%}, mean final distance {dist * 1e3:.1f} mm")
    print(f"zero tension: success {rate0:.0%}, mean final distance {dist0 * 1e3:.1f} mm")

    # The monitor files: a JSON comment line, the header "r,l,t", then one
    # row per episode (return, length, wall time since the start).
    rows = [np.loadtxt(f, delimiter=",", skiprows=2, ndmin=2)
            for f in args.out.glob("*monitor.csv")]
    episodes = np.concatenate(rows)
    episodes = episodes[np.argsort(episodes[:, 2])]
    try:
        import matplotlib
    except ImportError:
        print("(matplotlib not installed: no learning curve drawn)")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    s = np.cumsum(episodes[:, 1])
    r = episodes[:, 0]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(s, r, ".", ms=2, alpha=0.4, label="episode return")
    w = 50
    if len(r) >= w:
        ax.plot(s[w - 1:], np.convolve(r, np.ones(w) / w, "valid"), label=f"mean of {w}")
    ax.set_xlabel("environment steps")
    ax.set_ylabel("return (−Σ d/L − effort)")
    ax.set_title(f"PPO on softrod/Reach-v0: success {rate:.0%} after {args.steps} steps, "
                 f"{wall / 60:.1f} min", fontsize=9)
    ax.legend()
    path = args.out / "train_reach_ppo.png"
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
