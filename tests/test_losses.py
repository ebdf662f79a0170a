import pytest
import torch

from bipedal_cli.losses import (
    actor_loss,
    quantile_fractions,
    quantile_huber_loss,
    quantile_huber_loss_pairwise,
    temperature_loss,
    truncated_target,
)

from .reference import (
    ref_actor_loss,
    ref_critic_loss,
    ref_target,
    ref_temperature_loss,
)

f64 = torch.float64


def sorted_target(B, K, scale, gen):
    return torch.sort(torch.randn(B, K, dtype=f64, generator=gen) * scale, dim=1).values


def test_quantile_fractions_are_bin_midpoints():
    assert torch.allclose(
        quantile_fractions(4, dtype=f64), torch.tensor([1, 3, 5, 7], dtype=f64) / 8
    )


@pytest.mark.parametrize("scale", [0.2, 1.0, 5.0])
def test_critic_loss_matches_reference_value_and_gradient(scale):
    gen = torch.Generator().manual_seed(1)
    B, N, M, K = 3, 2, 4, 6
    atoms = (torch.randn(B, N, M, dtype=f64, generator=gen) * scale).requires_grad_()
    target = sorted_target(B, K, scale, gen)
    ref = ref_critic_loss(atoms, target)
    (ref_grad,) = torch.autograd.grad(ref, atoms)
    for fn in (quantile_huber_loss, quantile_huber_loss_pairwise):
        value = fn(atoms, target)
        (grad,) = torch.autograd.grad(value, atoms)
        assert value.item() == pytest.approx(ref.item(), rel=1e-12, abs=1e-14)
        assert torch.allclose(grad, ref_grad, rtol=1e-10, atol=1e-14)


def test_critic_loss_handles_ties_and_unit_distances():
    # Targets exactly at theta, theta +- 1 and repeated: the range boundaries of the fast path.
    atoms = torch.tensor([[[0.0, 1.0, 2.0]]], dtype=f64, requires_grad=True)
    target = torch.tensor([[-1.0, 0.0, 0.0, 1.0, 2.0, 3.0, 3.0]], dtype=f64)
    ref = ref_critic_loss(atoms, target)
    (ref_grad,) = torch.autograd.grad(ref, atoms)
    value = quantile_huber_loss(atoms, target)
    (grad,) = torch.autograd.grad(value, atoms)
    assert value.item() == pytest.approx(ref.item(), rel=1e-12)
    assert torch.allclose(grad, ref_grad, rtol=1e-10, atol=1e-14)


def test_fast_critic_loss_matches_pairwise_at_paper_sizes_in_float32():
    gen = torch.Generator().manual_seed(2)
    B, N, M = 64, 5, 25
    K = N * M - 2 * N
    atoms = (torch.randn(B, N, M, generator=gen) * 20 + 10).requires_grad_()
    target = torch.sort(torch.randn(B, K, generator=gen) * 20 + 10, dim=1).values
    fast = quantile_huber_loss(atoms, target)
    (g_fast,) = torch.autograd.grad(fast, atoms)
    atoms64 = atoms.detach().double().requires_grad_()
    exact = quantile_huber_loss_pairwise(atoms64, target.double())
    (g_exact,) = torch.autograd.grad(exact, atoms64)
    assert fast.dtype == torch.float32 and g_fast.dtype == torch.float32
    assert fast.item() == pytest.approx(exact.item(), rel=1e-6)
    assert torch.allclose(g_fast.double(), g_exact.double(), rtol=1e-5, atol=1e-12)


def test_critic_loss_rejects_a_target_with_gradient():
    atoms = torch.zeros(1, 1, 2, requires_grad=True)
    with pytest.raises(ValueError, match="target"):
        quantile_huber_loss(atoms, torch.zeros(1, 3, requires_grad=True))


def test_truncated_target_matches_reference():
    gen = torch.Generator().manual_seed(3)
    B, N, M, k = 4, 3, 5, 2
    next_atoms = torch.randn(B, N, M, dtype=f64, generator=gen) * 3
    reward = torch.randn(B, dtype=f64, generator=gen)
    terminated = torch.tensor([0.0, 1.0, 0.0, 1.0], dtype=f64)
    log_prob = torch.randn(B, dtype=f64, generator=gen)
    got = truncated_target(next_atoms, reward, terminated, log_prob, 0.3, 0.98, k)
    want = ref_target(next_atoms, reward, terminated, log_prob, 0.3, 0.98, k)
    assert got.shape == (B, N * M - k * N)
    assert torch.allclose(got, want, rtol=0, atol=1e-12)
    assert torch.all(got[:, 1:] >= got[:, :-1]), "the target must come out sorted"


def test_termination_cuts_the_bootstrap_but_truncation_does_not():
    next_atoms = torch.full((2, 2, 3), 10.0, dtype=f64)
    reward = torch.tensor([1.0, 1.0], dtype=f64)
    log_prob = torch.zeros(2, dtype=f64)
    # Row 0: terminated (fell). Row 1: the time limit cut it; stored as terminated = 0.
    y = truncated_target(next_atoms, reward, torch.tensor([1.0, 0.0]), log_prob, 0.5, 0.9, 1)
    assert torch.all(y[0] == 1.0)
    assert torch.allclose(y[1], torch.full_like(y[1], 1.0 + 0.9 * 10.0))


def test_truncation_drops_the_largest_atoms():
    next_atoms = torch.arange(12, dtype=f64).reshape(1, 2, 6)  # pooled 0..11
    y = truncated_target(
        next_atoms,
        torch.zeros(1, dtype=f64),
        torch.zeros(1),
        torch.zeros(1, dtype=f64),
        0.0,
        1.0,
        2,
    )
    assert y.tolist() == [[float(v) for v in range(8)]]  # 2 per net x 2 nets dropped: 8..11


def test_actor_loss_matches_reference_value_and_gradient():
    gen = torch.Generator().manual_seed(4)
    log_prob = torch.randn(3, dtype=f64, generator=gen).requires_grad_()
    atoms = torch.randn(3, 2, 4, dtype=f64, generator=gen).requires_grad_()
    got = actor_loss(log_prob, atoms, 0.7)
    want = ref_actor_loss(log_prob, atoms, 0.7)
    g_got = torch.autograd.grad(got, (log_prob, atoms))
    g_want = torch.autograd.grad(want, (log_prob, atoms))
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    for a, b in zip(g_got, g_want, strict=True):
        assert torch.allclose(a, b, rtol=1e-12)


def test_temperature_loss_matches_reference_and_moves_alpha_the_right_way():
    log_prob = torch.tensor([-1.0, 0.5, 2.0], dtype=f64, requires_grad=True)
    log_alpha = torch.tensor(0.2, dtype=f64, requires_grad=True)
    got = temperature_loss(log_alpha, log_prob, -4.0)
    want = ref_temperature_loss(log_alpha, log_prob, -4.0)
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    got.backward()
    assert log_prob.grad is None or torch.all(log_prob.grad == 0), "only alpha may move"
    # Entropy estimate -log pi = -0.5 on average, above H_T = -4: dJ/dlog(alpha) = 3.5 > 0, so
    # gradient descent lowers alpha.
    assert log_alpha.grad.item() == pytest.approx(3.5, rel=1e-12)


@pytest.mark.parametrize("dtype", [torch.float32, torch.float64])
def test_sort_rows_matches_torch_sort(dtype):
    from bipedal_cli.losses import sort_rows

    gen = torch.Generator().manual_seed(3)
    x = torch.randint(-20, 20, (64, 125), generator=gen).to(dtype) / 4  # many ties
    assert torch.equal(sort_rows(x), torch.sort(x, dim=1).values)
    assert sort_rows(x).dtype == dtype
    g = x.clone().requires_grad_(True)  # inside autograd: torch.sort's path
    assert torch.equal(sort_rows(g), torch.sort(x, dim=1).values)


@pytest.mark.parametrize("K", [1, 2, 7, 8, 115, 128])
def test_count_below_matches_searchsorted_left_and_right(K):
    from bipedal_cli.losses import count_below

    gen = torch.Generator().manual_seed(K)
    y = torch.sort(torch.randint(-8, 8, (16, K), generator=gen).to(f64) / 2, dim=1).values
    q = torch.randint(-20, 20, (16, 40), generator=gen).to(f64) / 2  # ties, below and above all
    w = torch.cat([q[:, :30], -q[:, :1] * 0.0], 1)  # another width, and -0.0 against +0.0
    strict, weak = count_below(y, q, w)
    assert torch.equal(strict, torch.searchsorted(y, q, side="left"))
    assert torch.equal(weak, torch.searchsorted(y, w, side="right"))


def test_anchor_loss_matches_reference_value_and_gradient():
    from bipedal_cli.anchor import anchor_loss

    from .reference import ref_anchor_loss

    gen = torch.Generator().manual_seed(11)
    action = torch.rand(5, 4, dtype=torch.float64, generator=gen).mul(2).sub(1).requires_grad_()
    anchor = torch.rand(5, 4, dtype=torch.float64, generator=gen).mul(2).sub(1).requires_grad_()
    got, want = anchor_loss(action, anchor), ref_anchor_loss(action, anchor)
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    (g_got,) = torch.autograd.grad(got, action)
    (g_want,) = torch.autograd.grad(want, action)
    assert torch.allclose(g_got, g_want, rtol=1e-12, atol=0)
    assert torch.allclose(g_got, 2 * (action - anchor).detach() / 5, rtol=1e-12)
    assert anchor_loss(action, anchor).grad_fn is not None
    assert not torch.autograd.grad(anchor_loss(action, anchor), anchor, allow_unused=True)[0]


def test_kl_anchor_loss_matches_reference_value_and_gradient():
    from bipedal_cli.anchor import kl_anchor_loss

    from .reference import ref_kl_anchor_loss

    gen = torch.Generator().manual_seed(12)
    mean, mean0 = (torch.randn(5, 4, dtype=torch.float64, generator=gen) for _ in range(2))
    log_std, log_std0 = (torch.randn(5, 4, dtype=torch.float64, generator=gen) for _ in range(2))
    mean.requires_grad_(), log_std.requires_grad_()
    got = kl_anchor_loss(mean, log_std, mean0, log_std0)
    want = ref_kl_anchor_loss(mean, log_std, mean0, log_std0)
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    g_got = torch.autograd.grad(got, (mean, log_std))
    g_want = torch.autograd.grad(want, (mean, log_std))
    for a, b in zip(g_got, g_want, strict=True):
        assert torch.allclose(a, b, rtol=1e-12, atol=0)
    normal = torch.distributions.Normal  # and torch's own KL of the two Gaussians
    kl = torch.distributions.kl_divergence(
        normal(mean, log_std.exp()), normal(mean0, log_std0.exp())
    )
    assert got.item() == pytest.approx(kl.sum(-1).mean().item(), rel=1e-12)
    assert kl_anchor_loss(mean0, log_std0, mean0, log_std0).item() == 0.0  # zero at the anchor
