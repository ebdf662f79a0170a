"""Scales for the actor's smoothness term and the target entropy's decay, measured on a training
state (`restart.pt` or `state.pt`) at the states its deterministic policy visits on Hardcore
(docs/hardcore.md, session 49).

    python benchmarks/actor_smoothness.py runs/hardcore/buffer2m-seed0-at-1000000/state.pt \\
        --seed 90000000 --episodes 10 --sigma 0.005 0.01 0.02 0.05

It prints, over those states s and a = mu(s), the deterministic action:

* the pull of the actor's objective on the action, ||grad_a J(s, a)||_2, where J is the mean of
  the lowest c N M pooled atoms (the risk-averse actor's objective, c = ``--fraction``) and
  also the mean of all atoms (eq. 2). The smoothness term lambda ||mu(s) - mu(s~)||_2 pulls
  the action at s with a force of exactly lambda, so lambda / ||grad_a J|| is how strong the
  term is against the critics;
* for each sigma, ||mu(s) - mu(s + sigma xi)||_2 with xi ~ N(0, I): how far a jitter of the
  observation moves the action now;
* the policy's entropy -log pi(a|s) at those states (its target, -dim(A) = -4 by default, is
  what the temperature holds it to) and the temperature alpha.

The printed lines and the machine go to benchmarks/results/actor_smoothness-<date>.json. One
thread; the jitter and the policy's draws are seeded by ``--seed``. Its default block,
90,000,000 on, is for measurements like this one: no selection plays it.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

import numpy as np
import torch
from record import run_recorded

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from critic_guided import lowest_atoms_mean  # noqa: E402

from bipedal_cli.agent import TQCAgent  # noqa: E402
from bipedal_cli.checkpoint import load_checkpoint  # noqa: E402
from bipedal_cli.config import config_from_dict  # noqa: E402
from bipedal_cli.evaluation import run_episodes, summarize  # noqa: E402
from bipedal_cli.schedule import actor_lowest_atoms  # noqa: E402


def visited_states(agent: TQCAgent, cfg, seeds: list[int]) -> tuple[torch.Tensor, dict]:
    """The observations the deterministic policy acts on in one episode per seed: (S, D)."""
    seen: list[np.ndarray] = []

    def policy(obs: np.ndarray) -> np.ndarray:
        seen.append(obs.copy())
        return agent.act(obs, deterministic=True)

    results = run_episodes(policy, cfg.env, seeds, cfg.agent)
    return torch.as_tensor(np.concatenate(seen)), summarize(results, cfg.train.solved_threshold)


def objective_pull(agent: TQCAgent, obs: torch.Tensor, lowest: int) -> torch.Tensor:
    """||grad_a J(s, a)||_2 at a = mu(s) for each state: (S,). J is the mean of the lowest
    ``lowest`` pooled atoms (all N M: eq. 2's mean)."""
    with torch.no_grad():
        action = agent.actor.deterministic(obs)  # (S, A)
    action.requires_grad_(True)
    objective = lowest_atoms_mean(agent.critic(obs, action), lowest)  # (S,)
    (grad,) = torch.autograd.grad(objective.sum(), action)  # (S, A)
    return grad.norm(dim=1)


@torch.no_grad()
def jitter_moves(agent: TQCAgent, obs: torch.Tensor, sigma: float, gen) -> torch.Tensor:
    """||mu(s) - mu(s + sigma xi)||_2 for each state: (S,)."""
    xi = torch.randn(obs.shape, generator=gen)
    return (agent.actor.deterministic(obs) - agent.actor.deterministic(obs + sigma * xi)).norm(
        dim=1
    )


def quartiles(x: torch.Tensor) -> str:
    q = torch.quantile(x.double(), torch.tensor([0.25, 0.5, 0.75], dtype=torch.float64))
    return f"mean {x.mean():.4g} (quartiles {q[0]:.4g} / {q[1]:.4g} / {q[2]:.4g})"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("state", type=Path, help="restart.pt or state.pt of a run")
    parser.add_argument("--seed", type=int, default=90_000_000)
    parser.add_argument("--episodes", type=int, default=10)
    parser.add_argument("--sigma", type=float, nargs="+", default=[0.005, 0.01, 0.02, 0.05])
    parser.add_argument("--fraction", type=float, default=0.25, help="c of the CVaR objective")
    args = parser.parse_args()
    torch.set_num_threads(1)
    torch.manual_seed(args.seed)
    data = load_checkpoint(args.state)
    cfg = config_from_dict(data["config"], f"STATE {args.state}: config")
    agent = TQCAgent(cfg.agent, int(data["obs_dim"]), int(data["act_dim"]))
    agent.load_state_dict(data["agent"])
    agent.actor.eval(), agent.critic.eval()
    seeds = list(range(args.seed, args.seed + args.episodes))
    obs, summary = visited_states(agent, cfg, seeds)
    step = int(data["counters"]["step"])
    n_atoms = cfg.agent.n_critics * cfg.agent.n_quantiles
    # the actor's own count of lowest atoms for a CVaR fraction c (schedule.py)
    risk = dataclasses.replace(cfg.agent, actor_cvar=args.fraction, actor_cvar_start=0)
    lowest = actor_lowest_atoms(1, risk)
    print(
        f"{args.state} at policy step {step:,}: {len(seeds)} episodes (seeds {seeds[0]}.."
        f"{seeds[-1]}), mean {summary['mean']:.1f}, {summary['falls']} fell; "
        f"{obs.shape[0]:,} states"
    )
    pull_lowest, pull_all = (objective_pull(agent, obs, n) for n in (lowest, n_atoms))
    print(f"  ||grad_a J||, lowest {lowest} of {n_atoms} atoms: {quartiles(pull_lowest)}")
    print(f"  ||grad_a J||, all atoms (eq. 2): {quartiles(pull_all)}")
    gen = torch.Generator().manual_seed(args.seed)
    for sigma in args.sigma:
        moved = jitter_moves(agent, obs, sigma, gen)
        print(f"  ||mu(s) - mu(s + {sigma:g} xi)||: {quartiles(moved)}")
    with torch.no_grad():
        _, log_prob = agent.actor.sample(obs, generator=gen)
    alpha = float(agent.log_alpha.detach().exp())
    print(f"  entropy -log pi(a|s): {quartiles(-log_prob)}; alpha {alpha:.4f}")


if __name__ == "__main__":
    run_recorded("actor_smoothness", main)
