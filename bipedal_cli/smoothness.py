"""The actor's smoothness term (``agent.actor_smooth``): the spatial term of CAPS (Mysore et al.
2021, "Regularizing Action Policies for Smooth Control"), a penalty on how far the deterministic
action moves when what the policy sees is jittered.

CAPS also has a temporal term, ||mu(s_t) - mu(s_{t+1})||, between successive states. It is not
built: with n-step returns the replay buffer stores (s_t, s_{t+n}), not s_{t+1}, and a gait's
successive actions are meant to differ.
"""

from __future__ import annotations

import torch

from .networks import SquashedGaussianActor


def smoothness_loss(action: torch.Tensor, jittered_action: torch.Tensor) -> torch.Tensor:
    """J_S = E_s ||mu(s) - mu(s~)||_2, the mean Euclidean distance between the deterministic
    action at each state and at its jittered copy s~ = s + sigma xi, xi ~ N(0, I).

    action, jittered_action: (B, A), both through the actor (the gradient reaches both, as in
    CAPS). At equal actions the norm's gradient is taken as zero.
    """
    return torch.linalg.vector_norm(action - jittered_action, dim=-1).mean()


def smoothness_penalty(
    actor: SquashedGaussianActor,
    obs: torch.Tensor,
    mean: torch.Tensor,
    noise: torch.Generator,
    weight: float,
    sigma: float,
) -> torch.Tensor:
    """lambda J_S on the batch's states, obs (B, D). mean, (B, A), is the actor's Gaussian mean
    before tanh at obs, from the forward pass that eq. 2's sample made (:meth:`sample_with_mean`),
    so mu(s) = tanh(mean) and only the B jittered states run through the actor again. xi is
    drawn from ``noise`` (the agent's checkpointed generator, so a resumed run draws the same
    jitter)."""
    xi = torch.randn(obs.shape, generator=noise, device=obs.device, dtype=obs.dtype)  # (B, D)
    jittered_action = actor.deterministic(obs + sigma * xi)  # (B, A)
    return weight * smoothness_loss(torch.tanh(mean), jittered_action)
