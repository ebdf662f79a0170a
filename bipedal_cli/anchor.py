"""The pull of a fine-tuned actor towards the policy its run started from (``train.init_policy``):
``agent.actor_anchor`` on the mean action, ``agent.actor_anchor_kl`` on the whole policy."""

from __future__ import annotations

import torch

from .config import AgentConfig
from .losses import anchor_loss, kl_anchor_loss
from .networks import SquashedGaussianActor


def anchored(cfg: AgentConfig) -> bool:
    """Whether the actor's loss pulls it towards the policy the run started from."""
    return cfg.actor_anchor is not None or cfg.actor_anchor_kl is not None


def anchor_penalty(
    actor: SquashedGaussianActor,
    anchor: SquashedGaussianActor,
    obs: torch.Tensor,
    cfg: AgentConfig,
) -> torch.Tensor | float:
    """beta ||mu - mu0||^2 (``actor_anchor``) + beta' KL(pi || pi0) (``actor_anchor_kl``) on the
    batch's states, obs (B, obs_dim); ``anchor`` is the initial actor, a constant."""
    penalty: torch.Tensor | float = 0.0
    with torch.no_grad():
        mean0, log_std0 = anchor.distribution_params(obs)  # (B, A) each
    mean, log_std = actor.distribution_params(obs)
    if cfg.actor_anchor is not None:
        penalty = cfg.actor_anchor * anchor_loss(torch.tanh(mean), torch.tanh(mean0))
    if cfg.actor_anchor_kl is not None:
        penalty = penalty + cfg.actor_anchor_kl * kl_anchor_loss(mean, log_std, mean0, log_std0)
    return penalty
