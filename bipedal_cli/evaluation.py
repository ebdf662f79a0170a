"""The deterministic evaluation protocol: episodes with fixed env seeds, policy batched over them.

"Solved" (the paper's criterion): the mean return of the deterministic policy tanh(mu(s)) over
100 episodes exceeds 300. Episodes are split over worker processes, and inside a worker the
policy runs on all of its episodes at once, one batched forward pass per env step.
"""

from __future__ import annotations

import multiprocessing as mp
import os
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import asdict, dataclass

import numpy as np
import torch

from .config import AgentConfig
from .envs import make_policy_env
from .terrain import KINDS, course_obstacles, fall_site


@dataclass
class EpisodeResult:
    seed: int
    ret: float
    length: int
    fell: bool
    fell_at: str | None = None  # stump | stairs | pit | flat (terrain.py) when it fell


def run_episodes(
    policy: Callable[[np.ndarray], np.ndarray],
    env_id: str,
    seeds: list[int],
    agent_cfg: AgentConfig | None = None,
) -> list[EpisodeResult]:
    """Run one episode per seed in lockstep; ``policy`` maps (B, obs_dim) to (B, act_dim).

    The env is the policy's (``agent_cfg``'s action repeat and observation history; none when
    None) with the env's own reward and time limit. Each episode gets a new env: a reused Box2D
    world carries history across resets, and the result of a seed should not depend on which
    episodes ran before it. Lengths are in env steps. A fall is put down to the obstacle
    nearest the hull (:func:`bipedal_cli.terrain.fall_site`).
    """
    agent_cfg = agent_cfg or AgentConfig()
    envs = [make_policy_env(env_id, agent_cfg) for _ in seeds]
    obs = np.stack([env.reset(seed=int(s))[0] for env, s in zip(envs, seeds, strict=True)])
    returns = np.zeros(len(seeds))
    lengths = np.zeros(len(seeds), dtype=int)
    fell = np.zeros(len(seeds), dtype=bool)
    fell_at: list[str | None] = [None] * len(seeds)
    active = np.ones(len(seeds), dtype=bool)
    while active.any():
        idx = np.flatnonzero(active)
        actions = policy(obs[idx].astype(np.float32))
        for j, i in enumerate(idx):
            o, r, term, trunc, info = envs[i].step(actions[j])
            obs[i] = o
            returns[i] += r
            lengths[i] += info["env_steps"]
            if term or trunc:
                active[i] = False
                fell[i] = info["fell"]
                if fell[i]:
                    course = envs[i].unwrapped
                    fell_at[i] = fall_site(course_obstacles(course), course.hull.position.x)
    for env in envs:
        env.close()
    return [
        EpisodeResult(int(s), float(r), int(n), bool(f), at)
        for s, r, n, f, at in zip(seeds, returns, lengths, fell, fell_at, strict=True)
    ]


def actor_policy(actor: torch.nn.Module, device: torch.device | str = "cpu"):
    """Wrap an actor's deterministic action as a numpy batch policy."""

    @torch.no_grad()
    def policy(obs: np.ndarray) -> np.ndarray:
        x = torch.as_tensor(obs, device=device)
        return actor.deterministic(x).cpu().numpy()

    return policy


def _cpu_actor(agent_cfg: AgentConfig, dims: tuple[int, int], actor_state: dict):
    from .networks import make_actor

    actor = make_actor(agent_cfg, *dims)
    actor.load_state_dict(actor_state)
    return actor.eval()


def _worker(
    agent_cfg: dict, dims: tuple[int, int], actor_state: dict, env_id: str, seeds: list[int]
) -> list[EpisodeResult]:
    torch.set_num_threads(1)
    cfg = AgentConfig(**agent_cfg)
    actor = _cpu_actor(cfg, dims, actor_state)
    return run_episodes(actor_policy(actor), env_id, seeds, cfg)


def evaluate_actor(
    actor,
    agent_cfg: AgentConfig,
    env_id: str,
    seeds: list[int],
    workers: int = 0,
    chunk: int = 5,
    on_episodes: Callable[[int], None] | None = None,
) -> list[EpisodeResult]:
    """Evaluate ``actor`` (on CPU) on one episode per seed; ``workers=0`` uses every core.

    ``on_episodes(n)`` is called as chunks of episodes finish (for progress bars). Workers are
    spawned processes, so a script that calls this (or ``train(..., until_solved=True)``) needs
    Python's ``if __name__ == "__main__":`` guard.
    """
    workers = workers or min(os.cpu_count() or 1, max(1, len(seeds) // chunk))
    state = {k: v.detach().cpu() for k, v in actor.state_dict().items()}
    dims = (actor.obs_dim, actor.act_dim)
    chunks = [seeds[i : i + chunk] for i in range(0, len(seeds), chunk)]
    if workers <= 1:
        on_cpu = next(actor.parameters()).device.type == "cpu"
        policy = actor_policy(actor if on_cpu else _cpu_actor(agent_cfg, dims, state))
        results = []
        threads = torch.get_num_threads()
        torch.set_num_threads(1)  # batch-of-5 inference: more threads only contend
        try:
            for part_seeds in chunks:
                part = run_episodes(policy, env_id, part_seeds, agent_cfg)
                results += part
                if on_episodes:
                    on_episodes(len(part))
        finally:
            torch.set_num_threads(threads)
        return results
    results_by_chunk: dict[int, list[EpisodeResult]] = {}
    ctx = mp.get_context("spawn")  # fork after torch has started threads can hang
    with ProcessPoolExecutor(workers, mp_context=ctx) as pool:
        futures = {
            pool.submit(_worker, asdict(agent_cfg), dims, state, env_id, c): i
            for i, c in enumerate(chunks)
        }
        for fut in as_completed(futures):
            part = fut.result()
            results_by_chunk[futures[fut]] = part
            if on_episodes:
                on_episodes(len(part))
    return [r for i in range(len(chunks)) for r in results_by_chunk[i]]


def summarize(results: list[EpisodeResult], threshold: float = 300.0) -> dict:
    returns = np.array([r.ret for r in results])
    lengths = np.array([r.length for r in results])
    return {
        "episodes": len(results),
        "mean": float(returns.mean()),
        "std": float(returns.std()),
        "min": float(returns.min()),
        "max": float(returns.max()),
        "median": float(np.median(returns)),
        "mean_length": float(lengths.mean()),
        "falls": int(sum(r.fell for r in results)),
        "falls_at": {k: n for k in KINDS if (n := sum(r.fell_at == k for r in results))},
        "threshold": threshold,
        "solved": bool(returns.mean() > threshold),
    }


def mean_interval(episodes: int, mean: float, std: float, z: float = 1.96) -> tuple[float, float]:
    """The normal-approximation interval for a policy's expected return from ``episodes``
    returns with mean ``mean`` and population standard deviation ``std`` (``summarize``'s):

        mean +- z std / sqrt(episodes - 1)        z = 1.96: 95%
    """
    half = z * std / max(episodes - 1, 1) ** 0.5
    return mean - half, mean + half


def paired_difference(a: list[EpisodeResult], b: list[EpisodeResult]) -> dict:
    """Policy A's mean return minus policy B's over the same env seeds, with a 95% interval.

    Both played each seed, so the interval is that of the mean of the per-seed differences
    d_s = R_A(s) - R_B(s) (:func:`mean_interval` on them): a course that is long or hard for both
    lowers both returns and leaves d_s alone, so the pairs tell two close policies apart with
    no more episodes than either played.
    """
    if [r.seed for r in a] != [r.seed for r in b]:
        raise ValueError("paired_difference: the two policies played different seeds")
    d = np.array([x.ret - y.ret for x, y in zip(a, b, strict=True)])  # (S,)
    low, high = mean_interval(len(d), float(d.mean()), float(d.std()))
    return {"episodes": len(d), "mean": float(d.mean()), "low": low, "high": high}
