"""From how far before a fall can the current policy still avoid it? The evidence behind
``train.fall_restart_back_min`` and ``train.fall_restart_back`` (docs/hardcore.md, session 22).

    python benchmarks/restart_back.py runs/hardcore/lrdecay-cvar25-g99-restarts-seed0 \\
        --back 2 5 10 15 20 30 45 60

Reads the falls a run remembers (its ``state.pt``) and its ``policy.pt``; for each back-off k,
rebuilds every remembered fall k policy steps before its end (the fallen episode's seed and
actions replayed on a new env, as a restart does) and lets the deterministic policy act for
k + 30 policy steps or to the episode's end. Prints, per k, how many of those restarts fell.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint  # noqa: E402
from bipedal_cli.envs import make_env  # noqa: E402
from bipedal_cli.evaluation import actor_policy  # noqa: E402
from bipedal_cli.fall_restarts import restart_length  # noqa: E402


def falls_again(cfg, policy, seed: int, actions: np.ndarray, back: int, after: int = 30) -> bool:
    """Whether the policy falls when it takes over ``back`` policy steps before the end of the
    fallen episode (seed, actions), within ``back + after`` policy steps."""
    a = cfg.agent
    env = make_env(cfg.env, action_repeat=a.action_repeat, history=a.history)
    try:
        obs, _ = env.reset(seed=seed)
        for action in actions[: restart_length(len(actions), back)]:
            obs, *_ = env.step(action)
        for _ in range(back + after):
            obs, _, terminated, truncated, info = env.step(policy(obs[None].astype(np.float32))[0])
            if terminated or truncated:
                return bool(info["fell"])
        return False
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a run directory with state.pt and policy.pt")
    parser.add_argument("--back", type=int, nargs="+", default=[2, 5, 10, 15, 20, 30, 45, 60])
    args = parser.parse_args()
    torch.set_num_threads(1)
    state = load_checkpoint(args.run / "state.pt")
    falls = [(int(f["seed"]), f["actions"].numpy()) for f in state.get("fall_memory") or []]
    step = int(state["counters"]["step"])
    del state  # the replay buffer: about 0.8 GB
    actor, cfg = actor_from_checkpoint(load_checkpoint(args.run / "policy.pt"))
    policy = actor_policy(actor)
    print(f"{len(falls)} remembered falls, policy at step {step:,}\n")
    print("| policy steps back | restarts | fell again |")
    print("|---|---|---|")
    for back in args.back:
        tries = [falls_again(cfg, policy, s, acts, back) for s, acts in falls if len(acts) > back]
        print(f"| {back} | {len(tries)} | {sum(tries)} ({np.mean(tries):.0%}) |")


if __name__ == "__main__":
    main()
