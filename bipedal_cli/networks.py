"""D2RL networks: a dense MLP ensemble, the squashed-Gaussian actor and the quantile critics.

D2RL (Sinha et al. 2020) concatenates the network input x to the output of every hidden layer
except the last::

    h_1 = relu(W_1 x + b_1)
    h_l = relu(W_l [h_{l-1}, x] + b_l)        l = 2..L
    out = W_o h_L + b_o

``W_l [h, x]`` equals ``W_l^h h + W_l^x x``, so the x-parts of every layer of every ensemble
member are computed by one matrix product up front, and each member's hidden layers are batched
matrix products over the ensemble dimension: N critics cost one call per layer, not N.
"""

from __future__ import annotations

import math
from typing import Any

import torch
from torch import nn
from torch.nn import functional as F


class DenseEnsemble(nn.Module):
    """``ensemble`` independent (D2RL or plain) MLPs that share their input.

    Parameters, per layer l (E members, H hidden, P layers that read x: L with D2RL, else 1):
    ``w_x[l]`` (in_dim, E*H) the x-part, ``w_h[l-1]`` (E, H, H) the h-part, ``b[l]`` (E, 1, H);
    ``w_out`` (E, H, out_dim), ``b_out`` (E, 1, out_dim). Separate tensors per layer: slicing one
    packed tensor would cost a zero-fill and a copy of its gradient in every backward pass.
    Initialisation matches ``nn.Linear``: U(-1/sqrt(fan_in), 1/sqrt(fan_in)) per member, with
    fan_in = H + in_dim for the layers that see the concatenated input.
    """

    def __init__(
        self,
        in_dim: int,
        out_dim: int,
        hidden: int,
        n_layers: int,
        ensemble: int = 1,
        d2rl: bool = True,
    ) -> None:
        super().__init__()
        self.in_dim, self.out_dim, self.hidden = in_dim, out_dim, hidden
        self.n_layers, self.ensemble, self.d2rl = n_layers, ensemble, d2rl
        E, H = ensemble, hidden
        n_proj = n_layers if d2rl else 1  # layers that read x directly
        self.w_x = nn.ParameterList(
            [nn.Parameter(torch.empty(in_dim, E * H)) for _ in range(n_proj)]
        )
        self.w_h = nn.ParameterList(
            [nn.Parameter(torch.empty(E, H, H)) for _ in range(n_layers - 1)]
        )
        self.b = nn.ParameterList([nn.Parameter(torch.empty(E, 1, H)) for _ in range(n_layers)])
        self.w_out = nn.Parameter(torch.empty(E, H, out_dim))
        self.b_out = nn.Parameter(torch.empty(E, 1, out_dim))
        self.reset_parameters()

    def _fan_in(self, layer: int) -> int:
        if layer == 0:
            return self.in_dim
        return self.hidden + (self.in_dim if self.d2rl else 0)

    @torch.no_grad()
    def reset_parameters(self) -> None:
        for layer in range(self.n_layers):
            bound = 1.0 / math.sqrt(self._fan_in(layer))
            if layer < len(self.w_x):
                self.w_x[layer].uniform_(-bound, bound)
            if layer > 0:
                self.w_h[layer - 1].uniform_(-bound, bound)
            self.b[layer].uniform_(-bound, bound)
        bound = 1.0 / math.sqrt(self.hidden)
        self.w_out.uniform_(-bound, bound)
        self.b_out.uniform_(-bound, bound)

    def forward(self, x: torch.Tensor, detach_params: bool = False) -> torch.Tensor:
        """x: (B, in_dim) -> (B, ensemble, out_dim).

        ``detach_params`` runs the same function with the parameters cut from autograd: the actor
        loss needs dQ/da through the critics but no gradient for the critics' weights, and this
        skips computing them.
        """

        def p(t: torch.Tensor) -> torch.Tensor:
            return t.detach() if detach_params else t

        B, E, H = x.shape[0], self.ensemble, self.hidden

        def x_part(layer: int) -> torch.Tensor:  # W_l^x x for every member: (E, B, H)
            return (x @ p(self.w_x[layer])).view(B, E, H).transpose(0, 1)

        h = F.relu(x_part(0) + p(self.b[0]))  # (E, B, H)
        for layer in range(1, self.n_layers):
            bias = p(self.b[layer])
            pre = bias + x_part(layer) if self.d2rl else bias.expand(E, B, H)
            h = F.relu(torch.baddbmm(pre, h, p(self.w_h[layer - 1])))  # (E, B, H)
        out = torch.baddbmm(p(self.b_out), h, p(self.w_out))  # (E, B, out_dim)
        return out.transpose(0, 1)  # (B, E, out_dim)


class SquashedGaussianActor(nn.Module):
    """pi(a|s): u ~ N(mu(s), sigma(s)^2), a = tanh(u); deterministic action tanh(mu(s))."""

    def __init__(
        self,
        obs_dim: int,
        act_dim: int,
        hidden: int = 512,
        n_layers: int = 2,
        d2rl: bool = True,
        log_std_min: float = -20.0,
        log_std_max: float = 2.0,
    ) -> None:
        super().__init__()
        self.obs_dim, self.act_dim = obs_dim, act_dim
        self.net = DenseEnsemble(obs_dim, 2 * act_dim, hidden, n_layers, 1, d2rl)
        self.log_std_min, self.log_std_max = log_std_min, log_std_max

    def distribution_params(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """obs: (B, obs_dim) -> mean, log_std: (B, act_dim) each, log_std clamped."""
        out = self.net(obs)[:, 0]  # (B, 2 * act_dim)
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
        u, eps, log_std = self._pre_tanh(obs, generator, eps)
        return torch.tanh(u), squashed_gaussian_log_prob(u, eps, log_std)

    def sample_action(
        self, obs: torch.Tensor, generator: torch.Generator | None = None
    ) -> torch.Tensor:
        """The action of :meth:`sample` alone, (B, A): exploration needs no log pi."""
        return torch.tanh(self._pre_tanh(obs, generator, None)[0])

    def _pre_tanh(
        self, obs: torch.Tensor, generator: torch.Generator | None, eps: torch.Tensor | None
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """u = mu + sigma * eps, with eps and log sigma: (B, A) each."""
        mean, log_std = self.distribution_params(obs)
        if eps is None:
            eps = torch.randn(mean.shape, generator=generator, device=mean.device, dtype=mean.dtype)
        return mean + log_std.exp() * eps, eps, log_std


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
    """N distributional critics Z_psi_n(s, a), each M quantile atoms: output (B, N, M)."""

    def __init__(
        self,
        obs_dim: int,
        act_dim: int,
        hidden: int = 256,
        n_layers: int = 2,
        n_critics: int = 5,
        n_quantiles: int = 25,
        d2rl: bool = True,
    ) -> None:
        super().__init__()
        self.n_critics, self.n_quantiles = n_critics, n_quantiles
        self.net = DenseEnsemble(obs_dim + act_dim, n_quantiles, hidden, n_layers, n_critics, d2rl)

    def forward(
        self, obs: torch.Tensor, act: torch.Tensor, detach_params: bool = False
    ) -> torch.Tensor:
        """obs: (B, obs_dim), act: (B, act_dim) -> atoms theta: (B, N, M)."""
        return self.net(torch.cat([obs, act], dim=-1), detach_params=detach_params)


def make_actor(cfg: Any, obs_dim: int, act_dim: int) -> SquashedGaussianActor:
    """The actor of an :class:`~bipedal_cli.config.AgentConfig` (``cfg``)."""
    return SquashedGaussianActor(
        obs_dim, act_dim, cfg.actor_hidden, cfg.n_layers, cfg.d2rl, cfg.log_std_min, cfg.log_std_max
    )
