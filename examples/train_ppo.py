"""A few minutes of PPO in swarm's Gymnasium environment, against a random policy, on small buildings.

    pip install 'swarm-sim[rl]' stable-baselines3 torch      # a CPU build of torch is enough
    python examples/train_ppo.py --timesteps 80000 --out ppo-results

One robot explores a 24 x 24 m building (a new map every episode: the map follows the episode's seed)
choosing, once a second (``ticks_per_step = 10``), one of 8 sectors of ``swarm/Explore-v0``'s goal
actions: it drives to the nearest frontier cell there (see ``sector_actions``). It sees the goal choices
and its pose. The reward is the area its lidar reveals (m^2, x 0.1). After training, the learned policy
(its most likely action, and sampled), a uniformly random one and the runtime's own frontier explorer (the
env's ``delegate`` action) each run the same evaluation maps, seeds the training never saw. Prints explored fraction after 60 s and ticks to 90 % explored (mean +- standard deviation
over the evaluation seeds) and the training wall and CPU time, writes them to OUT/results.json and draws
OUT/explored.png (mean explored fraction over time, with the spread).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

import swarm.env as senv  # registers swarm/Explore-v0

ENV = {"robots": 1, "size": 24, "ticks_per_step": 10, "reward": {"own": 0.1},
       "stop": {"explored": 0.95, "max_ticks": 1200}}
HORIZON_TICKS = 600  # explored fraction after 60 s


KEYS = ("choices", "pose")
"""What the policy sees of the observation: the goal choices and its own state (the 32 x 32 map crop, flattened
into a small network, slows learning more than it informs a one-robot policy)."""


def sector_actions(env):
    """The example's action set: one of the 8 sectors, each step. A sector without a frontier cell becomes
    the nearest sector (by angle) that has one, so no action is a no-op while any frontier is in view (a
    deterministic policy that picked a no-op would repeat it for ever); with none in view the robot keeps
    its goal. Both the learned and the random policy act through it."""
    import gymnasium as gym

    class SectorActions(gym.ActionWrapper):
        def __init__(self, inner):
            super().__init__(inner)
            self.action_space = gym.spaces.Discrete(8)
            self._mask = np.ones(9, dtype=np.int8)

        def reset(self, **kwargs):
            obs, info = self.env.reset(**kwargs)
            self._mask = info["action_mask"]
            return obs, info

        def step(self, action):
            obs, reward, terminated, truncated, info = self.env.step(self.action(action))
            self._mask = info["action_mask"]
            return obs, reward, terminated, truncated, info

        def action(self, sector):
            valid = np.flatnonzero(self._mask[1:9])
            if valid.size == 0:
                return 0
            gap = np.minimum((valid - int(sector)) % 8, (int(sector) - valid) % 8)
            return 1 + int(valid[np.argmin(gap)])

    return SectorActions(env)


def make_env(**extra):
    import gymnasium as gym
    from gymnasium.wrappers import FilterObservation

    env = FilterObservation(gym.make("swarm/Explore-v0", **{**ENV, **extra}), list(KEYS))
    return env if extra.get("delegate") else sector_actions(env)


def evaluate(policy, seeds: list[int], delegate: bool = False) -> list[dict]:
    """One episode per seed; ``policy(obs, info, rng) -> action``. Explored fraction over ticks, per seed."""
    out = []
    env = make_env(delegate=delegate)
    for seed in seeds:
        obs, info = env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        ticks, explored = [info["tick"]], [info["explored"]]
        done = False
        while not done:
            obs, _, terminated, truncated, info = env.step(policy(obs, info, rng))
            ticks.append(info["tick"])
            explored.append(info["explored"])
            done = terminated or truncated
        out.append({"seed": seed, "ticks": ticks, "explored": explored})
    env.close()
    return out


def summary(episodes: list[dict]) -> dict:
    """Mean and standard deviation over episodes of the explored fraction at HORIZON_TICKS and of the ticks
    to 90 % (episodes that never got there count at the tick limit and are counted)."""
    at = [float(np.interp(HORIZON_TICKS, e["ticks"], e["explored"])) for e in episodes]
    to90, missed = [], 0
    for e in episodes:
        hit = [t for t, x in zip(e["ticks"], e["explored"]) if x >= 0.9]
        to90.append(hit[0] if hit else ENV["stop"]["max_ticks"])
        missed += not hit
    return {"explored_at_60s_mean": float(np.mean(at)), "explored_at_60s_sd": float(np.std(at, ddof=1)),
            "ticks_to_90_mean": float(np.mean(to90)), "ticks_to_90_sd": float(np.std(to90, ddof=1)),
            "missed_90": missed, "episodes": len(episodes), "explored_at_60s": at}


def paired(a: dict, b: dict) -> dict:
    """Policy a against b on the same maps: mean and standard deviation of the per-map difference of the
    explored fraction at 60 s, and on how many maps a explored more, less, the same."""
    d = np.array(a["explored_at_60s"]) - np.array(b["explored_at_60s"])
    return {"diff_mean": float(d.mean()), "diff_sd": float(d.std(ddof=1)), "more": int((d > 0).sum()),
            "less": int((d < 0).sum()), "same": int((d == 0).sum())}


def plot(curves: dict[str, list[dict]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    grid = np.arange(0, ENV["stop"]["max_ticks"] + 1, 10)
    fig, ax = plt.subplots(figsize=(6, 3.6), dpi=120)
    for name, episodes in curves.items():
        ys = np.array([np.interp(grid, e["ticks"], e["explored"]) for e in episodes])
        mean, sd = ys.mean(axis=0), ys.std(axis=0, ddof=1)
        ax.plot(grid / 10, mean, label=name)
        ax.fill_between(grid / 10, mean - sd, mean + sd, alpha=0.2)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("explored fraction")
    ax.set_title(f"one robot, 24 x 24 m buildings, {len(next(iter(curves.values())))} evaluation maps")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--timesteps", type=int, default=80_000, help="PPO environment steps (1 s of simulated time each)")
    ap.add_argument("--eval-seeds", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path("ppo-results"))
    ap.add_argument("--evaluate", type=Path, default=None, metavar="MODEL.zip",
                    help="evaluate a saved model instead of training one (episodes are deterministic: the same model "
                         "and seeds give the same figures)")
    args = ap.parse_args()

    import torch
    from stable_baselines3 import PPO

    torch.set_num_threads(1)  # small networks: one thread is faster and leaves the other core alone
    args.out.mkdir(parents=True, exist_ok=True)
    if args.evaluate is None:
        env = make_env()
        env.reset(seed=args.seed)  # training episodes then draw their seeds (maps) from this one
        model = PPO("MultiInputPolicy", env, n_steps=512, batch_size=64, n_epochs=10, learning_rate=3e-4, gamma=0.95,
                    ent_coef=0.01, seed=args.seed, verbose=0, device="cpu", policy_kwargs={"net_arch": [64, 64]})
        t0, c0 = time.perf_counter(), time.process_time()
        model.learn(total_timesteps=args.timesteps)
        train_s, train_cpu_s = time.perf_counter() - t0, time.process_time() - c0
        model.save(args.out / "ppo_explore")
    else:
        model, train_s, train_cpu_s = PPO.load(args.evaluate, device="cpu"), None, None

    seeds = [1_000_000 + k for k in range(args.eval_seeds)]  # maps the training never saw
    curves = {"PPO (argmax)": evaluate(lambda obs, info, rng: int(model.predict(obs, deterministic=True)[0]), seeds)}
    torch.manual_seed(args.seed)  # the sampled policy draws from torch's generator
    curves |= {
        "PPO (sampled)": evaluate(lambda obs, info, rng: int(model.predict(obs, deterministic=False)[0]), seeds),
        "random": evaluate(lambda obs, info, rng: int(rng.integers(8)), seeds),
        "frontier explorer": evaluate(lambda obs, info, rng: 9, seeds, delegate=True),  # the delegate action
    }
    policies = {name: summary(eps) for name, eps in curves.items()}
    results = {"timesteps": args.timesteps if args.evaluate is None else None, "train_wall_s": train_s,
               "train_cpu_s": train_cpu_s, "env": ENV, "policies": policies,
               "paired_vs_random": {name: paired(policies[name], policies["random"])
                                    for name in policies if name != "random"}}
    (args.out / "results.json").write_text(json.dumps(results, indent=1))
    plot(curves, args.out / "explored.png")
    if train_s is not None:
        print(f"PPO: {args.timesteps} steps in {train_s:.0f} s of training ({train_cpu_s:.0f} s of CPU)")
    for name, s in policies.items():
        print(f"{name:18s} explored at 60 s {s['explored_at_60s_mean']:.3f} +- {s['explored_at_60s_sd']:.3f}, "
              f"ticks to 90 % {s['ticks_to_90_mean']:.0f} +- {s['ticks_to_90_sd']:.0f} "
              f"({s['missed_90']} of {s['episodes']} never reached 90 %)")
    for name, d in results["paired_vs_random"].items():
        print(f"{name} - random, same maps: {d['diff_mean']:+.3f} +- {d['diff_sd']:.3f} explored at 60 s; "
              f"more on {d['more']}, less on {d['less']} of {d['more'] + d['less'] + d['same']} maps")


if __name__ == "__main__":
    main()
