"""n-step transitions and their target against a slow float64 reference (tests/reference.py)."""

import numpy as np
import pytest
import torch

from bipedal_cli.losses import quantile_huber_loss, truncated_target
from bipedal_cli.nstep import NStepAccumulator

from .reference import ref_critic_loss, ref_nstep_target

f64 = torch.float64


def run_episode(n, gamma, rewards, terminated_at_end):
    """Push one episode of obs = [t] through the accumulator; the transitions in output order."""
    acc = NStepAccumulator(n, gamma)
    out = []
    T = len(rewards)
    for t in range(T):
        last = t == T - 1
        out += acc.push(
            np.array([t], np.float32),
            np.array([0.0], np.float32),
            rewards[t],
            np.array([t + 1], np.float32),
            terminated=last and terminated_at_end,
            truncated=last and not terminated_at_end,
        )
    return out


@pytest.mark.parametrize("terminated_at_end", [True, False])
@pytest.mark.parametrize("n,T", [(1, 4), (3, 7), (3, 2), (4, 4)])
def test_nstep_target_matches_reference_value_and_gradient(n, T, terminated_at_end):
    """Termination inside the n steps cuts the sum and the bootstrap; truncation cuts the sum
    and still bootstraps. Values and the critic loss's gradient, in float64."""
    gen = torch.Generator().manual_seed(n * 10 + T)
    gamma, alpha, k, N, M = 0.97, 0.3, 1, 2, 3
    rewards = [float(r) for r in torch.randn(T, generator=gen, dtype=f64) * 3]
    transitions = run_episode(n, gamma, rewards, terminated_at_end)
    assert [int(tr.obs[0]) for tr in transitions] == list(range(T))  # each step once, in order

    B = T
    next_atoms = torch.randn(B, N, M, dtype=f64, generator=gen)
    next_log_prob = torch.randn(B, dtype=f64, generator=gen)
    reward = torch.tensor([tr.reward for tr in transitions], dtype=f64)
    discount = torch.tensor([tr.discount for tr in transitions], dtype=f64)
    terminated = torch.tensor([float(tr.terminated) for tr in transitions], dtype=f64)
    fast = truncated_target(
        next_atoms, reward, terminated, next_log_prob, alpha, gamma, k, discount
    )
    ref = torch.stack(
        [
            ref_nstep_target(
                next_atoms[t],
                rewards,
                n,
                gamma,
                T - 1,
                terminated_at_end,
                next_log_prob[t],
                alpha,
                k,
                t,
            )
            for t in range(T)
        ]
    )
    assert torch.allclose(fast, ref, rtol=1e-12, atol=1e-12)
    # the bootstrap state is s_{t+m}
    assert [int(tr.next_obs[0]) for tr in transitions] == [min(t + n, T) for t in range(T)]

    atoms = torch.randn(B, N, M, dtype=f64, generator=gen).requires_grad_()
    (grad,) = torch.autograd.grad(quantile_huber_loss(atoms, fast), atoms)
    (ref_grad,) = torch.autograd.grad(ref_critic_loss(atoms, ref), atoms)
    assert torch.allclose(grad, ref_grad, rtol=1e-10, atol=1e-14)


def test_one_step_discount_equals_the_plain_target():
    """n = 1 through the accumulator gives what the one-step target computes from d."""
    transitions = run_episode(1, 0.98, [1.0, -2.0, 0.5], terminated_at_end=True)
    assert [tr.discount for tr in transitions] == [0.98, 0.98, 0.0]
    assert [tr.terminated for tr in transitions] == [False, False, True]


def test_accumulator_holds_at_most_n_minus_one_steps_between_pushes():
    acc = NStepAccumulator(3, 0.9)
    for t in range(5):
        ready = acc.push(np.zeros(1), np.zeros(1), 1.0, np.zeros(1), False, False)
        assert len(acc.pending) == min(t + 1, 2)
        assert len(ready) == (1 if t >= 2 else 0)
    assert ready[0].reward == pytest.approx(1 + 0.9 + 0.81)
    assert ready[0].discount == pytest.approx(0.9**3)
