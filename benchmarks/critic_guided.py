"""Act with the critics' help at test time: of K candidate actions (the deterministic action
and K - 1 draws from the policy's squashed Gaussian), take the one whose lowest atoms are
highest, on `bipedal eval`'s protocol (docs/hardcore.md, session 20).

    a*(s) = argmax_{a in {tanh(mu), tanh(mu + sigma eps_1), ..., tanh(mu + sigma eps_{K-1})}}
            (1 / L) sum_{i <= L} z_(i)(s, a)

where z_(1) <= ... <= z_(NM) are the N critics' M atoms pooled and sorted and
L = max(1, floor(c N M + 1/2)), the actor's own rule for its CVaR fraction c (schedule.py).
K = 1 is the plain deterministic policy. The actor and critics come from one training state
(`restart.pt` or `state.pt`), so they were trained together. On the gamma-0.99 run's state at
1,944,373 it did not cut the falls (docs/hardcore.md, session 20).

    python benchmarks/critic_guided.py \\
        checkpoints/restarts/hardcore-lrdecay-cvar25-g99-seed0-rerun.pt --candidates 64 \\
        --seed 23000000 --episodes 200

One process, one thread; the draws are seeded, so a run is reproducible.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint  # noqa: E402
from bipedal_cli.config import config_from_dict  # noqa: E402
from bipedal_cli.evaluation import run_episodes, summarize  # noqa: E402
from bipedal_cli.networks import QuantileCritics  # noqa: E402


def lowest_atoms_mean(atoms: torch.Tensor, fraction: float) -> torch.Tensor:
    """atoms: (B, N, M) -> (1 / L) sum_{i <= L} z_(i), L = max(1, floor(c N M + 1/2)): (B,)."""
    pooled = atoms.flatten(1).sort(dim=1).values  # (B, N M)
    lowest = max(1, math.floor(fraction * pooled.shape[1] + 0.5))
    return pooled[:, :lowest].mean(1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("state", type=Path, help="restart.pt or state.pt of a run")
    parser.add_argument("--candidates", type=int, default=16)
    parser.add_argument("--fraction", type=float, default=0.25, help="c: the lowest atoms' share")
    parser.add_argument("--seed", type=int, default=23_000_000)
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    torch.set_num_threads(1)
    data = load_checkpoint(args.state)
    actor, cfg = actor_from_checkpoint(data)
    a = config_from_dict(data["config"]).agent
    critic = QuantileCritics(
        int(data["obs_dim"]), int(data["act_dim"]), a.critic_hidden, a.n_layers,
        a.n_critics, a.n_quantiles, a.d2rl,
    )  # fmt: skip
    critic.load_state_dict(data["agent"]["critic"])
    critic.eval()
    noise = torch.Generator().manual_seed(args.seed)
    k = args.candidates

    @torch.no_grad()
    def policy(obs):  # (B, obs_dim) -> (B, act_dim)
        x = torch.as_tensor(obs)
        mean, log_std = actor.distribution_params(x)  # (B, A) each
        eps = torch.randn((k - 1, *mean.shape), generator=noise)  # (K-1, B, A)
        draws = torch.tanh(mean + log_std.exp() * eps)  # (K-1, B, A)
        cands = torch.cat([torch.tanh(mean)[None], draws])  # (K, B, A)
        if k == 1:
            return cands[0].numpy()
        b = x.shape[0]
        atoms = critic(x.repeat(k, 1), cands.reshape(k * b, -1))  # (K B, N, M)
        score = lowest_atoms_mean(atoms, args.fraction).reshape(k, b)  # (K, B)
        return cands[score.argmax(0), torch.arange(b)].numpy()  # (B, A)

    seeds = list(range(args.seed, args.seed + args.episodes))
    results = []
    for i in range(0, len(seeds), 10):
        results += run_episodes(policy, cfg.env, seeds[i : i + 10], cfg.agent)
    s = summarize(results, cfg.train.solved_threshold)
    print(f"{args.state}, {k} candidates, c {args.fraction}: env seeds {seeds[0]}..{seeds[-1]}")
    print(
        f"  {s['mean']:.1f} +- {s['std']:.1f}, median {s['median']:.1f}, falls {s['falls']} "
        f"{s['falls_at']}, mean length {s['mean_length']:.0f}"
    )
    if args.json:
        returns = [r.ret for r in results]
        args.json.write_text(json.dumps({"summary": s, "seeds": seeds, "returns": returns}))


if __name__ == "__main__":
    main()
