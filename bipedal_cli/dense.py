"""D2RL dense networks: an ensemble of MLPs that share their input.

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
