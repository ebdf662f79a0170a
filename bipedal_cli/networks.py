"""The squashed-Gaussian actor and the quantile critics over D2RL dense networks
(:mod:`~bipedal_cli.dense`), and their factories from an agent config."""

from __future__ import annotations

import math
from typing import Any

import torch
from torch import nn
from torch.nn import functional as F

from .dense import DenseEnsemble
from .encoders import make_encoder


class SquashedGaussianActor(nn.Module):
    """pi(a|s): u ~ N(mu(s), sigma(s)^2), a = tanh(u); deterministic action tanh(mu(s)).

    With an ``encoder`` (:mod:`~bipedal_cli.encoders`) the dense network reads encoder(s), and
    the actor's loss trains both.
    """

    def __init__(
        self,
        obs_dim: int,
        act_dim: int,
        hidden: int = 512,
        n_layers: int = 2,
        d2rl: bool = True,
        log_std_min: float = -20.0,
        log_std_max: float = 2.0,
        encoder: nn.Module | None = None,
    ) -> None:
        super().__init__()
        self.obs_dim, self.act_dim = obs_dim, act_dim
        self.encoder = encoder
        in_dim = obs_dim if encoder is None else encoder.out_dim
        self.net = DenseEnsemble(in_dim, 2 * act_dim, hidden, n_layers, 1, d2rl)
        self.log_std_min, self.log_std_max = log_std_min, log_std_max

    def distribution_params(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """obs: (B, obs_dim) -> mean, log_std: (B, act_dim) each, log_std clamped."""
        x = obs if self.encoder is None else self.encoder(obs)  # (B, in_dim)
        out = self.net(x)[:, 0]  # (B, 2 * act_dim)
        mean, log_std = out.chunk(2, dim=-1)
        return mean, log_std.clamp(self.log_std_min, self.log_std_max)

    def deterministic(self, obs: torch.Tensor) -> torch.Tensor:
        """The evaluation policy: tanh of the Gaussian's mean, (B, act_dim)."""
        mean, _ = self.distribution_params(obs)
        return torch.tanh(mean)

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.deterministic(obs)

    def sample(
        self,
        obs: torch.Tensor,
        generator: torch.Generator | None = None,
        eps: torch.Tensor | None = None,
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Reparameterised sample a = tanh(mu + sigma * eps) and log pi(a|s), (B, A) and (B,).

        eps ~ N(0, I), (B, A), is drawn from ``generator`` unless given (the agent draws the
        noise of a whole update up front, so that its two halves can run in two threads).
        """
        action, log_prob, _ = self.sample_with_mean(obs, generator, eps)
        return action, log_prob

    def sample_with_mean(
        self,
        obs: torch.Tensor,
        generator: torch.Generator | None = None,
        eps: torch.Tensor | None = None,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """:meth:`sample` and, from the same forward pass, the Gaussian's mean mu before tanh:
        (B, A), (B,), (B, A). The actor's smoothness term needs tanh(mu(s)) where eq. 2 samples;
        it applies the tanh itself, so an update without the term does no extra work."""
        u, eps, log_std, mean = self._pre_tanh(obs, generator, eps)
        return torch.tanh(u), squashed_gaussian_log_prob(u, eps, log_std), mean

    def sample_action(
        self, obs: torch.Tensor, generator: torch.Generator | None = None
    ) -> torch.Tensor:
        """The action of :meth:`sample` alone, (B, A): exploration needs no log pi."""
        return torch.tanh(self._pre_tanh(obs, generator, None)[0])

    def _pre_tanh(
        self, obs: torch.Tensor, generator: torch.Generator | None, eps: torch.Tensor | None
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        """u = mu + sigma * eps, with eps, log sigma and mu: (B, A) each."""
        mean, log_std = self.distribution_params(obs)
        if eps is None:
            eps = torch.randn(mean.shape, generator=generator, device=mean.device, dtype=mean.dtype)
        return mean + log_std.exp() * eps, eps, log_std, mean


def squashed_gaussian_log_prob(
    u: torch.Tensor, eps: torch.Tensor, log_std: torch.Tensor
) -> torch.Tensor:
    """log pi(tanh(u)) = sum_j [log N(u_j; mu_j, sigma_j) - log(1 - tanh(u_j)^2)], shape (B,).

    With u = mu + sigma * eps, log N(u; mu, sigma) = -eps^2/2 - log sigma - log(2 pi)/2, and
    log(1 - tanh(u)^2) = 2 (log 2 - u - softplus(-2u)) stays finite where tanh(u) rounds to +-1.
    """
    gaussian = -0.5 * eps.pow(2) - log_std - 0.5 * math.log(2 * math.pi)
    log_det = 2.0 * (math.log(2.0) - u - F.softplus(-2.0 * u))
    return (gaussian - log_det).sum(dim=-1)


class QuantileCritics(nn.Module):
    """N distributional critics Z_psi_n(s, a), each M quantile atoms: output (B, N, M).

    With an ``encoder`` the N critics share it: Z_psi_n(encoder(s), a), one encoding per batch.
    """

    def __init__(
        self,
        obs_dim: int,
        act_dim: int,
        hidden: int = 256,
        n_layers: int = 2,
        n_critics: int = 5,
        n_quantiles: int = 25,
        d2rl: bool = True,
        encoder: nn.Module | None = None,
    ) -> None:
        super().__init__()
        self.n_critics, self.n_quantiles = n_critics, n_quantiles
        self.encoder = encoder
        in_dim = (obs_dim if encoder is None else encoder.out_dim) + act_dim
        self.net = DenseEnsemble(in_dim, n_quantiles, hidden, n_layers, n_critics, d2rl)

    def forward(
        self, obs: torch.Tensor, act: torch.Tensor, detach_params: bool = False
    ) -> torch.Tensor:
        """obs: (B, obs_dim), act: (B, act_dim) -> atoms theta: (B, N, M).

        ``detach_params`` encodes obs without autograd: dZ/da needs no path through the
        encoder, whose input is data.
        """
        x = obs
        if self.encoder is not None:
            with torch.set_grad_enabled(torch.is_grad_enabled() and not detach_params):
                x = self.encoder(obs)  # (B, encoder.out_dim)
        return self.net(torch.cat([x, act], dim=-1), detach_params=detach_params)


def make_actor(cfg: Any, obs_dim: int, act_dim: int) -> SquashedGaussianActor:
    """The actor of an :class:`~bipedal_cli.config.AgentConfig` (``cfg``)."""
    return SquashedGaussianActor(
        obs_dim,
        act_dim,
        cfg.actor_hidden,
        cfg.n_layers,
        cfg.d2rl,
        cfg.log_std_min,
        cfg.log_std_max,
        make_encoder(cfg, obs_dim),
    )


def make_critics(cfg: Any, obs_dim: int, act_dim: int) -> QuantileCritics:
    """The critics of an :class:`~bipedal_cli.config.AgentConfig` (``cfg``)."""
    return QuantileCritics(
        obs_dim,
        act_dim,
        cfg.critic_hidden,
        cfg.n_layers,
        cfg.n_critics,
        cfg.n_quantiles,
        cfg.d2rl,
        make_encoder(cfg, obs_dim),
    )
