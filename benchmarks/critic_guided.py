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

    git show a434a40:checkpoints/restarts/hardcore-lrdecay-cvar25-g99-seed0-rerun.pt > g99-rerun.pt
    python benchmarks/critic_guided.py g99-rerun.pt --candidates 1 64 \\
        --seed 23000000 --episodes 600

(That restart file left the tree in session 28; git keeps it.)

Every K plays the same seeds, and the script prints each K's paired difference from the first.
The draws of each batch of 10 seeds are seeded by its first seed, so a seed's result does not
depend on the block it is played in or on the number of workers (one thread each).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import multiprocessing as mp
import sys
from pathlib import Path

import torch

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.agent import TQCAgent  # noqa: E402
from bipedal_cli.checkpoint import load_checkpoint  # noqa: E402
from bipedal_cli.config import config_from_dict  # noqa: E402
from bipedal_cli.evaluation import paired_difference, run_episodes, summarize  # noqa: E402
from bipedal_cli.schedule import actor_lowest_atoms  # noqa: E402


def lowest_atoms_mean(atoms: torch.Tensor, lowest: int) -> torch.Tensor:
    """atoms: (B, N, M) -> (1 / L) sum_{i <= L} z_(i) with L = ``lowest``: (B,)."""
    pooled = atoms.flatten(1).sort(dim=1).values  # (B, N M)
    return pooled[:, :lowest].mean(1)


BATCH = 10  # episodes in lockstep; the draws of a batch are seeded by its first env seed


def load_agent(path: Path, fraction: float):
    """The actor, the critics and the lowest-atom count L of a training state."""
    data = load_checkpoint(path)
    cfg = config_from_dict(data["config"], f"STATE {path}: config")
    agent = TQCAgent(cfg.agent, int(data["obs_dim"]), int(data["act_dim"]))
    agent.load_state_dict(data["agent"])
    # the actor's own count of lowest atoms for a CVaR fraction c (schedule.py)
    risk = dataclasses.replace(cfg.agent, actor_cvar=fraction, actor_cvar_start=0)
    return agent.actor.eval(), agent.critic.eval(), actor_lowest_atoms(1, risk), cfg


def play_batch(job: tuple[Path, float, int, list[int]]):
    """One batch of seeds with K candidates per step: a list of EpisodeResult."""
    path, fraction, k, seeds = job
    torch.set_num_threads(1)
    actor, critic, lowest, cfg = load_agent(path, fraction)
    noise = torch.Generator().manual_seed(seeds[0])

    @torch.no_grad()
    def policy(obs):  # (B, obs_dim) -> (B, act_dim)
        x = torch.as_tensor(obs)
        mean, log_std = actor.distribution_params(x)  # (B, A) each
        if k == 1:
            return torch.tanh(mean).numpy()
        eps = torch.randn((k - 1, *mean.shape), generator=noise)  # (K-1, B, A)
        draws = torch.tanh(mean + log_std.exp() * eps)  # (K-1, B, A)
        cands = torch.cat([torch.tanh(mean)[None], draws])  # (K, B, A)
        b = x.shape[0]
        atoms = critic(x.repeat(k, 1), cands.reshape(k * b, -1))  # (K B, N, M)
        score = lowest_atoms_mean(atoms, lowest).reshape(k, b)  # (K, B)
        return cands[score.argmax(0), torch.arange(b)].numpy()  # (B, A)

    return run_episodes(policy, cfg.env, seeds, cfg.agent)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("state", type=Path, help="restart.pt or state.pt of a run")
    parser.add_argument("--candidates", type=int, nargs="+", default=[1, 64], help="K, each")
    parser.add_argument("--fraction", type=float, default=0.25, help="c: the lowest atoms' share")
    parser.add_argument("--seed", type=int, default=23_000_000)
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--json", type=Path, default=None)
    args = parser.parse_args()
    _, _, _, cfg = load_agent(args.state, args.fraction)
    seeds = list(range(args.seed, args.seed + args.episodes))
    batches = [seeds[i : i + BATCH] for i in range(0, len(seeds), BATCH)]
    jobs = [(args.state, args.fraction, k, b) for k in args.candidates for b in batches]
    with mp.get_context("fork").Pool(args.workers) as pool:
        played = pool.map(play_batch, jobs, chunksize=1)
    by_k = {k: sum(played[i * len(batches) : (i + 1) * len(batches)], []) for i, k in
            enumerate(args.candidates)}  # fmt: skip
    print(f"{args.state}, c {args.fraction}: env seeds {seeds[0]}..{seeds[-1]}")
    out = {"seeds": seeds, "fraction": args.fraction, "candidates": {}}
    for k, results in by_k.items():
        s = summarize(results, cfg.train.solved_threshold)
        print(
            f"  K = {k}: {s['mean']:.1f} +- {s['std']:.1f}, median {s['median']:.1f}, falls "
            f"{s['falls']} {s['falls_at']}, mean length {s['mean_length']:.0f}"
        )
        out["candidates"][k] = {"summary": s, "returns": [r.ret for r in results]}
    first = args.candidates[0]
    for k in args.candidates[1:]:
        d = paired_difference(by_k[k], by_k[first])
        print(
            f"  K = {k} minus K = {first}: {d['mean']:+.1f} ({d['low']:+.1f} to {d['high']:+.1f})"
        )
    if args.json:
        args.json.write_text(json.dumps(out))


if __name__ == "__main__":
    main()
