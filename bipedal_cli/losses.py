"""TQC's losses and truncated target as pure functions of tensors (paper eqs. 1-3).

Symbols: B batch, N critics, M atoms per critic, K = N*M - k*N kept target atoms.
The device and dtype follow the inputs; nothing here touches an environment.

The quantile Huber loss is the hot spot of a TQC update: written pairwise it touches
B*N*M*K elements (64*5*25*115 = 920,000) several times, forward and backward.
:func:`quantile_huber_loss` computes the same value and gradient exactly in
O(B*N*M*log K) from the *sorted* target atoms (the truncated target is sorted anyway):
for a fixed atom theta the pairwise sum splits into four ranges of y (u = y - theta < -1,
-1 <= u < 0, 0 <= u <= 1, u > 1) where the summand is linear or quadratic in y, so prefix sums
of y and y^2 give it in closed form. :func:`quantile_huber_loss_pairwise` is the direct version.
"""

from __future__ import annotations

import functools

import numpy as np
import torch


def quantile_fractions(n_quantiles: int, device=None, dtype=torch.float32) -> torch.Tensor:
    """tau_m = (2m - 1) / (2M), m = 1..M: the midpoints of M equal quantile bins, shape (M,)."""
    m = torch.arange(1, n_quantiles + 1, device=device, dtype=dtype)
    return (2 * m - 1) / (2 * n_quantiles)


@functools.lru_cache(maxsize=8)
def _fractions_per_atom(
    n_critics: int, n_quantiles: int, device: torch.device
) -> tuple[torch.Tensor, torch.Tensor]:
    """tau and 1 - tau for the N*M atoms of (B, N, M) flattened, float64, made once per shape."""
    with torch.inference_mode(False), torch.no_grad():
        tau = quantile_fractions(n_quantiles, device, torch.float64).repeat(n_critics)
        return tau, 1 - tau


def truncated_target(
    next_atoms: torch.Tensor,
    reward: torch.Tensor,
    terminated: torch.Tensor,
    next_log_prob: torch.Tensor,
    alpha: torch.Tensor | float,
    gamma: float,
    drop_per_critic: int,
    discount: torch.Tensor | None = None,
) -> torch.Tensor:
    """Sorted target atoms y_i = r + gamma (1 - d) (z_(i)(s', a') - alpha log pi(a'|s')).

    n-step transitions (:mod:`bipedal_cli.nstep`) pass ``discount`` (B,) = gamma^m (1 - d) and
    their summed reward as ``reward``: y_i = R + discount (z_(i) - alpha log pi(a'|s_{t+m})).

    next_atoms: (B, N, M) target-critic atoms at (s', a'), a' ~ pi(.|s').
    z_(i) is the i-th smallest of the N*M pooled atoms; the k*N largest are dropped
    (i = 1..K, K = N*M - k*N). reward, terminated, next_log_prob: (B,).

    d is *termination* only (the walker fell or reached the end): a time-limit truncation
    bootstraps, because the state it cuts off still has a future.
    Returns (B, K), sorted ascending (a discount >= 0 keeps the order).
    """
    B, N, M = next_atoms.shape
    kept = N * M - drop_per_critic * N
    pooled = sort_rows(next_atoms.reshape(B, N * M))  # (B, N*M)
    z = pooled[:, :kept]  # (B, K)
    soft_z = z - alpha * next_log_prob.unsqueeze(1)  # (B, K)
    if discount is None:
        discount = gamma * (1.0 - terminated.to(z.dtype))  # (B,)
    return reward.unsqueeze(1) + discount.unsqueeze(1) * soft_z  # (B, K)


def sort_rows(x: torch.Tensor) -> torch.Tensor:
    """Each row of a (B, L) tensor in ascending order.

    On CPU, for tensors outside autograd, NumPy's vectorised sort: the same values as
    ``torch.sort`` about 20x faster at (64, 125) (``python benchmarks/micro.py``).
    """
    if x.device.type == "cpu" and not x.requires_grad:
        return torch.from_numpy(np.sort(x.numpy(), axis=1))
    return torch.sort(x, dim=1).values


def count_below(
    y: torch.Tensor, strict: torch.Tensor, weak: torch.Tensor
) -> tuple[torch.Tensor, torch.Tensor]:
    """#{j : y[b, j] < strict[b, i]} and #{j : y[b, j] <= weak[b, i]} for ascending rows y (B, K).

    strict: (B, S), weak: (B, W) -> (B, S), (B, W) int64: the integers of
    ``torch.searchsorted(y, strict, side="left")`` and ``(y, weak, side="right")``, in one
    branch-free binary search that moves every query together (a search with unpredictable
    branches stalls on each comparison; one search instead of two halves the small ops).
    ``y <= w`` is ``not (-y < -w)``, exact in floating point, so the weak queries search the
    reversed, negated rows with the same strict comparison, in the second half of one row::

        table[b] = [y_b, +inf ..., -reversed(y_b), +inf ...]      each half a power of 2 > K long

    A query's position starts at its half's first index and gains ``step`` for each probe
    ``table[position + step - 1]`` below it, step = half/2, ..., 1.
    """
    B, K = y.shape
    half = 2 ** K.bit_length()  # > K: the last probe of a half is +inf
    inf_pad = y.new_full((B, half - K), float("inf"))
    table = torch.cat([y, inf_pad, -y.flip(1), inf_pad], 1)  # (B, 2 * half)
    queries = torch.cat([strict, -weak], 1)  # (B, S + W)
    n_strict = strict.shape[1]
    position = torch.zeros(queries.shape, dtype=torch.long, device=y.device)  # (B, S + W)
    position[:, n_strict:] = half
    step = half // 2
    while step >= 1:  # invariant: the answer is in [position, position + 2 * step)
        probe = table[:, step - 1 :].gather(1, position)  # table[position + step - 1]: (B, S + W)
        position.add_(probe < queries, alpha=step)
        step //= 2
    below_strict = position[:, :n_strict]  # (B, S)
    above_weak = position[:, n_strict:] - half  # #{y > weak}: (B, W)
    return below_strict, K - above_weak


def quantile_huber_loss_pairwise(atoms: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Direct eq. (1): mean over b, n, m, i of rho_tau_m(y_i - theta_n^m), kappa = 1.

    rho_tau(u) = |tau - 1(u < 0)| * L_H(u), L_H(u) = u^2/2 if |u| <= 1 else |u| - 1/2.
    atoms theta: (B, N, M); target y: (B, K), no gradient. The mean over n is (1/N) sum_n of
    the per-critic losses J_Z(psi_n); Adam is invariant to that constant factor.
    """
    tau = quantile_fractions(atoms.shape[-1], atoms.device, atoms.dtype)  # (M,)
    u = target[:, None, None, :] - atoms[..., None]  # (B, N, M, K)
    abs_u = u.abs()
    huber = torch.where(abs_u <= 1.0, 0.5 * u.pow(2), abs_u - 0.5)
    weight = (tau[:, None] - (u < 0).to(u.dtype)).abs()  # (B, N, M, K)
    return (weight * huber).mean()


class _SortedQuantileHuber(torch.autograd.Function):
    """Eq. (1) and its gradient w.r.t. theta from sorted targets, in O(B N M log K)."""

    @staticmethod
    def forward(ctx, atoms: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
        B, N, M = atoms.shape
        K = target.shape[1]
        # float64 for the prefix sums: sums of y^2 would lose the small differences otherwise.
        y = target.detach().double()  # (B, K), ascending
        center = y.mean(dim=1, keepdim=True)  # (B, 1): shifting y and theta keeps u unchanged
        y = y - center
        theta = atoms.detach().double().reshape(B, N * M) - center  # (B, N*M)
        tau, one_minus_tau = _fractions_per_atom(N, M, atoms.device)  # (N*M,) each

        powers = torch.stack([y, y * y], 1)  # (B, 2, K): y_i and y_i^2
        prefix = torch.cat([powers.new_zeros(B, 2, 1), powers.cumsum(2)], 2)  # (B, 2, K+1)
        # #{u < -1}, #{u < 0} and #{u <= 1} for every atom: i0 <= i1 <= i2, (B, N*M) each
        strict, i2 = count_below(y, torch.cat([theta - 1.0, theta], 1), theta + 1.0)
        i0, i1 = strict.chunk(2, 1)
        bounds = torch.cat([strict, i2], 1).unsqueeze(1).expand(B, 2, 3 * N * M)
        # prefix[b, p, j] = sum_{i<j} y_i^(p+1); at the three bounds: (B, N*M) each
        s1, s2 = prefix.gather(2, bounds).unbind(1)  # (B, 3*N*M) each
        (s1_0, s1_1, s1_2), (s2_0, s2_1, s2_2) = s1.chunk(3, 1), s2.chunk(3, 1)
        sum_lo, sum_neg, sum_pos = s1_0, s1_1 - s1_0, s1_2 - s1_1  # sums of y over the ranges
        sum_hi = prefix[:, 0, K:] - s1_2
        sq_neg, sq_pos = s2_1 - s2_0, s2_2 - s2_1  # sums of y^2
        c0, c1, c2 = i0.double(), (i1 - i0).double(), (i2 - i1).double()  # range sizes
        c3 = K - i2.double()
        theta_sq, two_theta = theta**2, 2 * theta

        # sum_i |tau - 1(u<0)| L_H(u), range by range (u = y - theta):
        #   u < -1: (1 - tau)(theta - y - 1/2)       -1 <= u < 0: (1 - tau)(y - theta)^2 / 2
        #   0 <= u <= 1: tau (y - theta)^2 / 2       u > 1: tau (y - theta - 1/2)
        value = one_minus_tau * (
            c0 * (theta - 0.5) - sum_lo + 0.5 * (sq_neg - two_theta * sum_neg + c1 * theta_sq)
        ) + tau * (
            0.5 * (sq_pos - two_theta * sum_pos + c2 * theta_sq) + sum_hi - c3 * (theta + 0.5)
        )
        # d/dtheta: -sum_i |tau - 1(u<0)| clip(u, -1, 1)
        slope = one_minus_tau * (-c0 + sum_neg - c1 * theta) + tau * (sum_pos - c2 * theta + c3)
        count = B * N * M * K
        ctx.save_for_backward(slope)
        ctx.shape, ctx.count, ctx.dtype = atoms.shape, count, atoms.dtype
        return (value.sum() / count).to(atoms.dtype)

    @staticmethod
    def backward(ctx, grad_output: torch.Tensor):
        (slope,) = ctx.saved_tensors
        grad = (-slope / ctx.count).to(ctx.dtype).reshape(ctx.shape) * grad_output
        return grad, None


def quantile_huber_loss(atoms: torch.Tensor, target: torch.Tensor) -> torch.Tensor:
    """Eq. (1) averaged over the batch, critics, atoms m and target atoms i (see pairwise version).

    atoms theta: (B, N, M), requires grad; target y: (B, K), sorted ascending along K and
    detached (it is built under no_grad from the target critics). Exact, not an approximation:
    tests pin it to the pairwise float64 reference in value and gradient.
    """
    if target.requires_grad:
        raise ValueError("quantile_huber_loss: the target must not require grad")
    return _SortedQuantileHuber.apply(atoms, target)


def actor_loss(
    log_prob: torch.Tensor,
    atoms: torch.Tensor,
    alpha: torch.Tensor | float,
    lowest: int | None = None,
):
    """Eq. (2): J_pi = E[alpha log pi(a|s) - (1/NM) sum_{n,m} theta_n^m(s, a)], a ~ pi(.|s).

    log_prob: (B,), atoms: (B, N, M) at the re-parameterised action; alpha is a constant here.

    With ``lowest`` = L < N*M, the risk-averse objective (``agent.actor_cvar``):

        J_pi = E[alpha log pi(a|s) - (1/L) sum_{j=1..L} theta_(j)(s, a)]

    theta_(j) the j-th smallest of the N*M pooled atoms: each atom weighs 1/(NM) in the mixture
    of the N critics' distributions, so this is the mixture's CVaR at level L/(NM). The gradient
    reaches the L atoms that are lowest at the current action.
    """
    B, N, M = atoms.shape
    if lowest is None or lowest >= N * M:
        value = atoms.mean(dim=(1, 2))  # (B,)
    else:
        pooled = atoms.reshape(B, N * M)  # (B, N*M)
        value = torch.topk(pooled, lowest, dim=1, largest=False, sorted=False).values.mean(1)
    return (alpha * log_prob - value).mean()


def temperature_loss(log_alpha: torch.Tensor, log_prob: torch.Tensor, target_entropy: float):
    """Eq. (3): J(alpha) = E[log alpha * (-log pi(a|s) - H_T)].

    log_prob is detached: this loss moves only alpha. When the policy's entropy -log pi is
    above H_T the gradient lowers alpha, below it raises alpha.
    """
    return (log_alpha * (-log_prob.detach() - target_entropy)).mean()
