"""The range of every config value and of the CLI's counts and seeds, checked in one place.

:func:`validate` runs whenever a config is resolved (:func:`bipedal_cli.config.config_from_dict`:
YAML, ``--set``, and the config inside every checkpoint), so a bad value is one line naming its
key before anything is built or written.
"""

from __future__ import annotations

import os
import re
from typing import Any

from .agent_checks import agent_checks
from .errors import UserError

REPLAY_CHOICES = ("keep", "clear")  # curriculum.replay

SEED_LIMIT = 2**31  # env seeds, numpy and torch seeds: 0 <= seed < 2^31
OBS_SIZE, ACT_SIZE = 24, 4  # BipedalWalker(-Hardcore)-v3


def check_seeds(option: str, first: int, count: int = 1) -> None:
    """Seeds first .. first + count - 1 must lie in [0, 2^31): one line naming ``option``."""
    if not (0 <= first and first + count <= SEED_LIMIT):
        raise UserError(
            f"{option}: expected a seed in [0, {SEED_LIMIT - count}] (seeds {first} .. "
            f"{first + count - 1} are used)"
        )


MAX_EPISODES = 100_000  # per evaluation: 10^9 would exhaust memory before the first episode


def check_count(option: str, value: int, limit: int = MAX_EPISODES, low: int = 1) -> None:
    if not low <= value <= limit:
        raise UserError(f"{option} {value}: expected an integer in [{low}, {limit:,}]")


MAX_THREADS = 256  # torch.set_num_threads(100000) crashes the process


def replay_bytes(cfg: Any) -> int:
    """Memory of a full replay buffer: obs and next obs (H * 24), action, reward, flags."""
    per = 2 * cfg.agent.history * OBS_SIZE + ACT_SIZE + 3
    return cfg.train.buffer_size * per * 4


def physical_memory() -> int:
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (ValueError, OSError, AttributeError):
        return 1 << 50


def validate(cfg: Any, source: str) -> None:
    """Every value's range in ``cfg`` (a :class:`~bipedal_cli.config.Config`), checked when the
    config is resolved (also a checkpoint's config)."""
    a, t, c = cfg.agent, cfg.train, cfg.curriculum
    evals = max(t.eval_episodes, t.solved_episodes)
    checks = [
        *agent_checks(a, t.init_policy),
        (t.init_policy != "", "train.init_policy", "null or the path of a policy file"),
        (
            all(p != "" for p in t.refill_policies),
            "train.refill_policies",
            "a list of policy files' paths (empty: the restart's own actor)",
        ),
        (
            t.init_policy_sha256 is None or re.fullmatch("[0-9a-f]{64}", t.init_policy_sha256),
            "train.init_policy_sha256",
            "null or 64 lowercase hex digits (sha256sum's output)",
        ),
        (
            t.init_policy_sha256 is None or t.init_policy is not None,
            "train.init_policy_sha256",
            "null unless train.init_policy is set",
        ),
        (t.replay_curation_start >= 0, "train.replay_curation_start", "a non-negative integer"),
        (
            t.replay_recency is None or 0.0 < t.replay_recency < 1.0,
            "train.replay_recency",
            "null or a number in (0, 1) (ERE's eta_0, for example 0.996)",
        ),
        (
            t.replay_recency_end is None or t.replay_recency_end >= 1,
            "train.replay_recency_end",
            "null or a positive policy step (where eta reaches 1)",
        ),
        (t.replay_recent_min >= 1, "train.replay_recent_min", "a positive integer"),
        (t.obstacle_stump >= 0, "train.obstacle_stump", "a non-negative weight"),
        (t.obstacle_stairs >= 0, "train.obstacle_stairs", "a non-negative weight"),
        (t.obstacle_pit >= 0, "train.obstacle_pit", "a non-negative weight"),
        (
            t.obstacle_stump + t.obstacle_stairs + t.obstacle_pit > 0,
            "train.obstacle_pit",
            "weights of stump, stairs and pit with a positive sum",
        ),
        (t.obstacle_mix_start >= 0, "train.obstacle_mix_start", "a non-negative step"),
        (
            not t.mixes_obstacles() or t.fall_restart == 0,
            "train.fall_restart",
            "0 with an obstacle mix (a restart rebuilds a course from its seed alone)",
        ),
        (
            t.fall_penalty_final is None or t.fall_penalty is not None,
            "train.fall_penalty_final",
            "null unless train.fall_penalty is set (the ramp starts from it)",
        ),
        (t.fall_penalty_ramp_start >= 0, "train.fall_penalty_ramp_start", "a non-negative step"),
        (
            t.fall_penalty_ramp_end >= t.fall_penalty_ramp_start,
            "train.fall_penalty_ramp_end",
            "a step at or after train.fall_penalty_ramp_start",
        ),
        (0 <= t.fall_restart <= 1, "train.fall_restart", "a probability in [0, 1]"),
        (t.fall_restart_back_min >= 1, "train.fall_restart_back_min", "a positive integer"),
        (
            t.fall_restart_back >= t.fall_restart_back_min,
            "train.fall_restart_back",
            "an integer at least train.fall_restart_back_min",
        ),
        (
            t.fall_restart_horizon is None or t.fall_restart_horizon >= 1,
            "train.fall_restart_horizon",
            "null or a positive integer",
        ),
        (
            1 <= t.fall_restart_memory <= 100_000,
            "train.fall_restart_memory",
            "an integer in [1, 100,000]",
        ),
        (t.fall_restart_start >= 0, "train.fall_restart_start", "a non-negative step"),
        (0 <= t.fall_restart_probe <= 1, "train.fall_restart_probe", "a probability in [0, 1]"),
        (t.reward_scale > 0, "train.reward_scale", "a positive number"),
        (t.total_steps >= 0, "train.total_steps", "a non-negative integer"),
        (t.warmup_steps >= 0, "train.warmup_steps", "a non-negative integer"),
        (t.refill_steps >= 0, "train.refill_steps", "a non-negative integer"),
        (t.buffer_size >= 1, "train.buffer_size", "a positive integer"),
        (t.updates_per_step >= 0, "train.updates_per_step", "a non-negative integer"),
        (
            t.updates_per_step_final is None or 0 <= t.updates_per_step_final <= 64,
            "train.updates_per_step_final",
            "an integer in [0, 64] or null",
        ),
        (t.updates_per_step_start >= 0, "train.updates_per_step_start", "a non-negative step"),
        (t.eval_every >= 0, "train.eval_every", "a non-negative integer"),
        (t.eval_episodes >= 1, "train.eval_episodes", "a positive integer"),
        (t.solved_episodes >= 1, "train.solved_episodes", "a positive integer"),
        (t.checkpoint_every >= 0, "train.checkpoint_every", "a non-negative integer"),
        (
            0 <= t.threads <= MAX_THREADS,
            "train.threads",
            f"an integer in [0, {MAX_THREADS}] (0: every core)",
        ),
        (0 <= cfg.seed < SEED_LIMIT, "seed", f"an integer in [0, {SEED_LIMIT - 1}]"),
        (
            0 <= t.eval_seed <= SEED_LIMIT - evals,
            "train.eval_seed",
            f"an integer in [0, {SEED_LIMIT - evals}] (eval_seed + episodes < 2^31)",
        ),
        (
            evals <= MAX_EPISODES,
            "train.*_episodes",
            "at most 100000",
        ),
        (c.walker_steps >= 0, "curriculum.walker_steps", "a non-negative integer"),
        (c.hardcore_steps >= 0, "curriculum.hardcore_steps", "a non-negative integer"),
        (c.replay in REPLAY_CHOICES, "curriculum.replay", "keep or clear"),
        (
            cfg.device in ("auto", "cpu", "cuda") or cfg.device.startswith("cuda:"),
            "device",
            "auto, cpu or cuda",
        ),
    ]
    for ok, key, expected in checks:
        if not ok:
            raise UserError(f"{source}: key {key!r} expects {expected}")
    need, have = replay_bytes(cfg), physical_memory()
    if need > have:
        raise UserError(
            f"{source}: key 'train.buffer_size' expects a buffer that fits in memory: "
            f"{t.buffer_size:,} transitions need {need / 2**30:.1f} GiB, this machine has "
            f"{have / 2**30:.1f} GiB"
        )
