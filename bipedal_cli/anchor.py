"""The pull of a fine-tuned actor towards the policy its run started from (``train.init_policy``):
``agent.actor_anchor`` on the mean action, ``agent.actor_anchor_kl`` on the whole policy."""

from __future__ import annotations

import torch

from .config import AgentConfig
from .networks import SquashedGaussianActor


def anchor_loss(action: torch.Tensor, anchor_action: torch.Tensor) -> torch.Tensor:
    """The actor's distance from the policy a run started from (``agent.actor_anchor``):

        J_anchor = E_s[ sum_i (mu_i(s) - mu0_i(s))^2 ]

    mu(s) = tanh(mean) is the actor's deterministic action and mu0(s) the initial actor's, a
    constant; action, anchor_action: (B, A). TD3+BC's term, with the initial policy in place of
    the data's actions.
    """
    return (action - anchor_action.detach()).pow(2).sum(-1).mean()


def kl_anchor_loss(
    mean: torch.Tensor, log_std: torch.Tensor, mean0: torch.Tensor, log_std0: torch.Tensor
) -> torch.Tensor:
    """KL(pi || pi0) of the actor from the policy a run started from (``agent.actor_anchor_kl``):

        J_KL = E_s[ sum_i log(sigma0_i / sigma_i) + (sigma_i^2 + (mu_i - mu0_i)^2) / (2 sigma0_i^2)
                    - 1/2 ]

    mean, log_std: (B, A), the actor's Gaussian before tanh; mean0, log_std0 the initial actor's,
    constants. tanh is one-to-one, so this is also the KL of the squashed policies. Unlike
    :func:`anchor_loss` it holds the spread as well as the mean action.
    """
    mean0, log_std0 = mean0.detach(), log_std0.detach()
    var_ratio = torch.exp(2 * (log_std - log_std0))  # sigma^2 / sigma0^2
    shift = (mean - mean0).pow(2) * torch.exp(-2 * log_std0)  # (mu - mu0)^2 / sigma0^2
    return (log_std0 - log_std + 0.5 * (var_ratio + shift) - 0.5).sum(-1).mean()


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
