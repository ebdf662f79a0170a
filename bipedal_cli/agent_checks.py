"""The range of every value in a config's agent section (:func:`bipedal_cli.validation.validate`
checks them with the rest, in order, when a config is resolved)."""

from __future__ import annotations

import math
from typing import Any

ENCODERS = ("none", "lstm")  # agent.encoder: encoders.py


def agent_checks(a: Any, init_policy: str | None) -> list[tuple[bool, str, str]]:
    """(holds, key, what it expects) for every value of ``a``, an
    :class:`~bipedal_cli.agent_config.AgentConfig`; ``init_policy`` is ``train.init_policy``
    (an anchor needs the policy it anchors to)."""
    return [
        (0.0 < a.gamma <= 1.0, "agent.gamma", "a number in (0, 1]"),
        (a.lr > 0, "agent.lr", "a positive number"),
        (a.batch_size >= 1, "agent.batch_size", "a positive integer"),
        (0.0 < a.tau <= 1.0, "agent.tau", "a number in (0, 1]"),
        (a.n_critics >= 1, "agent.n_critics", "a positive integer"),
        (a.n_quantiles >= 1, "agent.n_quantiles", "a positive integer"),
        (
            0 <= a.drop_per_critic < a.n_quantiles,
            "agent.drop_per_critic",
            "an integer in [0, n_quantiles)",
        ),
        (a.actor_hidden >= 1, "agent.actor_hidden", "a positive width"),
        (a.critic_hidden >= 1, "agent.critic_hidden", "a positive width"),
        (a.n_layers >= 1, "agent.n_layers", "a positive integer"),
        (a.init_alpha > 0, "agent.init_alpha", "a positive number"),
        (a.log_std_min < a.log_std_max, "agent.log_std_min", "a number below agent.log_std_max"),
        (a.actor_hidden <= 65536, "agent.actor_hidden", "at most 65536"),
        (a.critic_hidden <= 65536, "agent.critic_hidden", "at most 65536"),
        (a.n_layers <= 64, "agent.n_layers", "at most 64"),
        (a.n_critics * a.n_quantiles <= 1 << 20, "agent.n_critics", "N * M <= 2^20 atoms"),
        (a.batch_size <= 1 << 20, "agent.batch_size", "at most 2^20"),
        (
            a.batch_size_final is None or 1 <= a.batch_size_final <= 1 << 20,
            "agent.batch_size_final",
            "null or an integer in [1, 2^20]",
        ),
        (a.batch_size_start >= 0, "agent.batch_size_start", "a non-negative step"),
        (a.action_repeat >= 1, "agent.action_repeat", "a positive integer"),
        (a.history >= 1, "agent.history", "a positive integer"),
        (a.encoder in ENCODERS, "agent.encoder", " or ".join(ENCODERS)),
        (1 <= a.encoder_hidden <= 4096, "agent.encoder_hidden", "an integer in [1, 4096]"),
        (a.n_step >= 1, "agent.n_step", "a positive integer"),
        (a.lr_final is None or a.lr_final >= 0, "agent.lr_final", "null or a number >= 0"),
        (a.lr_decay_start >= 0, "agent.lr_decay_start", "a non-negative integer"),
        (
            a.actor_cvar is None or 0.0 < a.actor_cvar <= 1.0,
            "agent.actor_cvar",
            "null or a number in (0, 1]",
        ),
        (a.actor_cvar_start >= 0, "agent.actor_cvar_start", "a non-negative step"),
        (a.actor_update_start >= 0, "agent.actor_update_start", "a non-negative step"),
        (
            a.actor_anchor is None or (a.actor_anchor > 0 and init_policy is not None),
            "agent.actor_anchor",
            "null, or a positive number with train.init_policy set (the actor it anchors to)",
        ),
        (
            a.actor_anchor_kl is None or (a.actor_anchor_kl > 0 and init_policy is not None),
            "agent.actor_anchor_kl",
            "null, or a positive number with train.init_policy set (the actor it anchors to)",
        ),
        (
            a.lr_final is None or a.lr_decay_end > a.lr_decay_start,
            "agent.lr_decay_end",
            "a step after agent.lr_decay_start (with agent.lr_final set)",
        ),
        (
            a.drop_per_critic_final is None or 0 <= a.drop_per_critic_final < a.n_quantiles,
            "agent.drop_per_critic_final",
            "null or an integer in [0, n_quantiles)",
        ),
        (a.drop_per_critic_start >= 0, "agent.drop_per_critic_start", "a non-negative step"),
        (
            a.target_entropy_final is None or math.isfinite(a.target_entropy_final),
            "agent.target_entropy_final",
            "null or a finite number (nats, for example -8)",
        ),
        (
            a.target_entropy_decay_start >= 0,
            "agent.target_entropy_decay_start",
            "a non-negative step",
        ),
        (
            a.target_entropy_final is None
            or a.target_entropy_decay_end >= a.target_entropy_decay_start,
            "agent.target_entropy_decay_end",
            "a step at or after agent.target_entropy_decay_start (with target_entropy_final set)",
        ),
        (
            a.actor_smooth is None or 0 < a.actor_smooth < math.inf,
            "agent.actor_smooth",
            "null or a positive number",
        ),
        (
            0 < a.actor_smooth_sigma < math.inf,
            "agent.actor_smooth_sigma",
            "a positive number (the jitter's standard deviation)",
        ),
        (a.actor_smooth_start >= 0, "agent.actor_smooth_start", "a non-negative step"),
    ]
