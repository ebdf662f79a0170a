"""Evaluate several policies of one run as an ensemble that acts with the mean of their
deterministic actions, a = (1 / K) sum_k tanh(mu_k(s)), on `bipedal eval`'s protocol
(docs/hardcore.md, session 4: it did not cut the falls).

    python benchmarks/action_ensemble.py runs/hardcore/lrdecay-seed0/policies/step-1240000.pt \\
        runs/hardcore/lrdecay-seed0/policies/step-1340000.pt \\
        runs/hardcore/lrdecay-seed0/policies/step-1500000.pt --seed 3000000

The policies must share the env, the action repeat and the observation history (the env
wrappers are the first one's). One process, one thread.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint  # noqa: E402
from bipedal_cli.evaluation import run_episodes, summarize  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("policies", type=Path, nargs="+")
    parser.add_argument("--seed", type=int, default=3_000_000)
    parser.add_argument("--episodes", type=int, default=100)
    args = parser.parse_args()
    torch.set_num_threads(1)
    loaded = [actor_from_checkpoint(load_checkpoint(p)) for p in args.policies]
    actors = [actor for actor, _ in loaded]
    cfg = loaded[0][1]
    if any(
        (c.env, c.agent.action_repeat, c.agent.history)
        != (cfg.env, cfg.agent.action_repeat, cfg.agent.history)
        for _, c in loaded
    ):
        raise SystemExit("the policies differ in env, action repeat or history")

    @torch.no_grad()
    def policy(obs):  # (B, obs_dim) -> (B, act_dim)
        x = torch.as_tensor(obs)
        return torch.stack([a.deterministic(x) for a in actors]).mean(0).numpy()  # (K, B, A)

    seeds = list(range(args.seed, args.seed + args.episodes))
    results = []
    for i in range(0, len(seeds), 10):
        results += run_episodes(policy, cfg.env, seeds[i : i + 10], cfg.agent)
    s = summarize(results, cfg.train.solved_threshold)
    names = ", ".join(p.name for p in args.policies)
    print(f"mean action of {names}: env seeds {seeds[0]}..{seeds[-1]}")
    print(
        f"  {s['mean']:.1f} +- {s['std']:.1f}, median {s['median']:.1f}, falls {s['falls']} "
        f"{s['falls_at']}"
    )


if __name__ == "__main__":
    main()
