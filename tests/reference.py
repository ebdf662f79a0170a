"""A slow reference written straight from the paper's equations, element by element, float64.

Nothing here is vectorised or shared with the package: loops over b, n, m, i exactly as the
sums in eqs. (1)-(3) are written, so that the fast code can be checked against it.
"""

from __future__ import annotations

import torch


def ref_tau(m: int, M: int) -> float:
    return (2 * m - 1) / (2 * M)  # m = 1..M


def ref_huber(u):
    return 0.5 * u * u if abs(u.item()) <= 1.0 else abs(u) - 0.5


def ref_rho(tau: float, u):
    indicator = 1.0 if u.item() < 0 else 0.0
    return abs(tau - indicator) * ref_huber(u)


def ref_target(next_atoms, reward, terminated, next_log_prob, alpha, gamma, k):
    """y_i = r + gamma (1 - d) (z_(i) - alpha log pi), z_(i) the kN... smallest pooled atoms."""
    B, N, M = next_atoms.shape
    out = []
    for b in range(B):
        pooled = sorted([next_atoms[b, n, m] for n in range(N) for m in range(M)], key=float)
        kept = pooled[: N * M - k * N]
        not_done = 1.0 - float(terminated[b])
        out.append(
            torch.stack(
                [reward[b] + gamma * not_done * (z - alpha * next_log_prob[b]) for z in kept]
            )
        )
    return torch.stack(out)


def ref_critic_loss(atoms, target):
    """mean_b (1/N) sum_n L^k(s_b, a_b; psi_n), L^k = 1/(K M) sum_m sum_i rho_tau_m(y_i - theta)."""
    B, N, M = atoms.shape
    K = target.shape[1]
    total = 0.0
    for b in range(B):
        for n in range(N):
            per_critic = 0.0
            for m in range(M):
                for i in range(K):
                    per_critic = per_critic + ref_rho(
                        ref_tau(m + 1, M), target[b, i] - atoms[b, n, m]
                    )
            total = total + per_critic / (K * M)
    return total / (B * N)


def ref_actor_loss(log_prob, atoms, alpha):
    B, N, M = atoms.shape
    total = 0.0
    for b in range(B):
        q = sum(atoms[b, n, m] for n in range(N) for m in range(M)) / (N * M)
        total = total + alpha * log_prob[b] - q
    return total / B


def ref_actor_cvar_loss(log_prob, atoms, alpha, lowest):
    """Eq. 2 with the mean of the ``lowest`` smallest of the N*M pooled atoms (CVaR)."""
    B, N, M = atoms.shape
    total = 0.0
    for b in range(B):
        pooled = [atoms[b, n, m] for n in range(N) for m in range(M)]
        pooled.sort(key=lambda z: z.item())
        q = sum(pooled[:lowest]) / lowest
        total = total + alpha * log_prob[b] - q
    return total / B


def ref_anchor_loss(action, anchor_action):
    """E_s[ sum_i (mu_i(s) - mu0_i(s))^2 ], mu0 a constant (agent.actor_anchor)."""
    B, A = action.shape
    total = 0.0
    for b in range(B):
        for i in range(A):
            total = total + (action[b, i] - anchor_action[b, i].item()) ** 2
    return total / B


def ref_kl_anchor_loss(mean, log_std, mean0, log_std0):
    """E_s[ sum_i KL(N(mu_i, sigma_i^2) || N(mu0_i, sigma0_i^2)) ], pi0 a constant."""
    import math

    B, A = mean.shape
    total = 0.0
    for b in range(B):
        for i in range(A):
            s, s0 = log_std[b, i].exp(), math.exp(log_std0[b, i].item())
            m0 = mean0[b, i].item()
            total = total + math.log(s0) - log_std[b, i]
            total = total + (s**2 + (mean[b, i] - m0) ** 2) / (2 * s0**2) - 0.5
    return total / B


def ref_temperature_loss(log_alpha, log_prob, target_entropy):
    B = log_prob.shape[0]
    total = 0.0
    for b in range(B):
        total = total + log_alpha * (-log_prob[b].item() - target_entropy)
    return total / B


def ref_nstep_target(
    next_atoms, rewards, n, gamma, end, terminated_at_end, next_log_prob, alpha, k, t
):
    """The n-step target of the transition at time t of one episode, straight from its definition.

    rewards: the episode's one-step rewards r_0..r_{T-1}; the episode ends after step ``end``
    (= T - 1), terminated or truncated. m = min(n, T - t) rewards are summed; the bootstrap at
    s_{t+m} is cut only when the episode terminated within them:

        y_i = sum_{j<m} gamma^j r_{t+j} + gamma^m (1 - d) (z_(i) - alpha log pi(a'|s_{t+m}))
    """
    T = end + 1
    m = min(n, T - t)
    ret = sum(gamma**j * float(rewards[t + j]) for j in range(m))
    d = 1.0 if (terminated_at_end and t + m == T) else 0.0
    N, M = next_atoms.shape
    pooled = sorted([next_atoms[i, j] for i in range(N) for j in range(M)], key=float)
    kept = pooled[: N * M - k * N]
    return torch.stack([ret + gamma**m * (1.0 - d) * (z - alpha * next_log_prob) for z in kept])


def ref_smoothness_loss(action, jittered_action):
    """E_s ||mu(s) - mu(s~)||_2 (agent.actor_smooth), both actions through the actor."""
    B, A = action.shape
    total = 0.0
    for b in range(B):
        squared = 0.0
        for i in range(A):
            squared = squared + (action[b, i] - jittered_action[b, i]) ** 2
        total = total + squared**0.5
    return total / B
