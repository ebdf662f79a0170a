"""The contents of checkpoint files, built and read: a policy file's payload, and where a training
state stands under a policy file's ``meta`` names (the files themselves are written and checked
by :mod:`bipedal_cli.checkpoint`)."""

from __future__ import annotations

from typing import Any

from .checkpoint import FORMAT_VERSION, POLICY_FORMAT


def policy_payload(
    actor_state: dict, config: dict, obs_dim: int, act_dim: int, meta: dict
) -> dict[str, Any]:
    return {
        "format": POLICY_FORMAT,
        "version": FORMAT_VERSION,
        "config": config,
        "env": config["env"],
        "obs_dim": obs_dim,
        "act_dim": act_dim,
        "actor": {k: v.detach().cpu().clone() for k, v in actor_state.items()},
        "meta": meta,
    }


def training_progress(data: dict[str, Any]) -> dict[str, Any]:
    """Where a checked training state stands, under a policy file's ``meta`` names: policy
    steps, env steps, episodes, wall time and its last and full evaluations."""
    c = data["counters"]
    return {
        "steps": c["step"],
        "env_steps": c.get("env_steps", c["step"]),
        "episodes": c["episodes"],
        "wall_time": round(c["wall_time"], 1),
        "last_eval": data["last_eval"],
        "full_eval": data["full_eval"],
    }
