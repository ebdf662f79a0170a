"""What the actor's loss adds to eq. (2): the pull towards the policy a fine-tuned run started
from (``agent.actor_anchor``, ``agent.actor_anchor_kl``: :mod:`~bipedal_cli.anchor`) and the
smoothness term (``agent.actor_smooth``: :mod:`~bipedal_cli.smoothness`)."""

from __future__ import annotations

from typing import Any

import torch

from .anchor import anchor_penalty
from .smoothness import smoothness_penalty


def actor_penalties(agent: Any, obs: torch.Tensor, mean: torch.Tensor) -> torch.Tensor | None:
    """The terms on for the update in progress, summed, on the batch's states obs (B, D), where
    the actor's Gaussian mean before tanh is mean (B, A), with its gradient; None
    when none is (the actor's loss is eq. 2 alone, to the bit). While the actor is frozen
    (``agent.actor_update_start``) it does not move, so none applies: it is its own anchor."""
    if agent.actor_frozen:
        return None
    penalty = None
    if agent.anchor is not None:
        penalty = anchor_penalty(agent.actor, agent.anchor, obs, agent.cfg)
    if agent.actor_smooth is not None:
        smooth = smoothness_penalty(
            agent.actor,
            obs,
            mean,
            agent.noise,
            agent.actor_smooth,
            agent.cfg.actor_smooth_sigma,
        )
        penalty = smooth if penalty is None else penalty + smooth
    return penalty
