"""The CUDA path: the losses against the float64 reference on the GPU, and CUDA runs that repeat
and resume to the bit, every Hardcore feature on.

Skipped where no CUDA GPU is present (CI has none). On a GPU machine:
    python -m pytest -q tests/test_cuda.py
"""

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.losses import (
    actor_loss,
    count_below,
    quantile_huber_loss,
    quantile_huber_loss_pairwise,
    truncated_target,
)
from bipedal_cli.resume import resume
from bipedal_cli.train import train

from .reference import ref_actor_cvar_loss, ref_actor_loss, ref_critic_loss, ref_target
from .test_hardcore_features import FEATURES, LSTM, featured
from .test_train import assert_states_equal

pytestmark = pytest.mark.skipif(not torch.cuda.is_available(), reason="needs a CUDA GPU")

f64 = torch.float64
GPU = "cuda"


def on_gpu(*tensors):
    """Copies on the GPU, leaves of their own graph where the original needs a gradient."""
    return [t.detach().to(GPU).requires_grad_(t.requires_grad) for t in tensors]


@pytest.mark.parametrize("scale", [0.2, 1.0, 5.0])
def test_critic_loss_on_the_gpu_matches_the_reference(scale):
    gen = torch.Generator().manual_seed(11)
    B, N, M, K = 3, 2, 4, 6
    atoms = (torch.randn(B, N, M, dtype=f64, generator=gen) * scale).requires_grad_()
    target = torch.sort(torch.randn(B, K, dtype=f64, generator=gen) * scale, dim=1).values
    ref = ref_critic_loss(atoms, target)
    (ref_grad,) = torch.autograd.grad(ref, atoms)
    for fn in (quantile_huber_loss, quantile_huber_loss_pairwise):
        gpu_atoms, gpu_target = on_gpu(atoms, target)
        value = fn(gpu_atoms, gpu_target)
        (grad,) = torch.autograd.grad(value, gpu_atoms)
        assert value.device.type == "cuda"
        assert value.item() == pytest.approx(ref.item(), rel=1e-12, abs=1e-14)
        assert torch.allclose(grad.cpu(), ref_grad, rtol=1e-10, atol=1e-14)


def test_fast_critic_loss_on_the_gpu_in_float32_at_paper_sizes():
    gen = torch.Generator().manual_seed(12)
    B, N, M = 64, 5, 25
    K = N * M - 2 * N
    atoms = torch.randn(B, N, M, generator=gen) * 20 + 10
    target = torch.sort(torch.randn(B, K, generator=gen) * 20 + 10, dim=1).values
    gpu_atoms, gpu_target = on_gpu(atoms.requires_grad_(), target)
    fast = quantile_huber_loss(gpu_atoms, gpu_target)
    (g_fast,) = torch.autograd.grad(fast, gpu_atoms)
    atoms64 = atoms.detach().double().requires_grad_()
    exact = quantile_huber_loss_pairwise(atoms64, target.double())
    (g_exact,) = torch.autograd.grad(exact, atoms64)
    assert fast.dtype == torch.float32
    assert fast.item() == pytest.approx(exact.item(), rel=1e-6)
    assert torch.allclose(g_fast.cpu().double(), g_exact, rtol=1e-5, atol=1e-12)


def test_count_below_on_the_gpu_matches_searchsorted():
    gen = torch.Generator().manual_seed(13)
    y = torch.sort(torch.randint(-5, 6, (8, 115), generator=gen).double(), dim=1).values
    strict = torch.randint(-6, 7, (8, 25), generator=gen).double()
    weak = torch.randint(-6, 7, (8, 25), generator=gen).double()
    below, at_most = count_below(*on_gpu(y, strict, weak))
    assert torch.equal(below.cpu(), torch.searchsorted(y, strict, side="left"))
    assert torch.equal(at_most.cpu(), torch.searchsorted(y, weak, side="right"))


def test_targets_on_the_gpu_match_the_reference_and_the_cpu_n_step_target():
    gen = torch.Generator().manual_seed(14)
    B, N, M, k = 4, 3, 5, 2
    next_atoms = torch.randn(B, N, M, dtype=f64, generator=gen) * 3
    reward = torch.randn(B, dtype=f64, generator=gen)
    terminated = torch.tensor([0.0, 1.0, 0.0, 1.0], dtype=f64)
    log_prob = torch.randn(B, dtype=f64, generator=gen)
    got = truncated_target(*on_gpu(next_atoms, reward, terminated, log_prob), 0.3, 0.98, k)
    want = ref_target(next_atoms, reward, terminated, log_prob, 0.3, 0.98, k)
    assert torch.allclose(got.cpu(), want, rtol=0, atol=1e-12)
    # n-step transitions: the CPU path is checked against ref_nstep_target in test_nstep.py
    discount = torch.tensor([0.97**3, 0.0, 0.97**2, 0.97], dtype=f64)
    cpu = truncated_target(next_atoms, reward, terminated, log_prob, 0.3, 0.97, k, discount)
    gpu = truncated_target(
        *on_gpu(next_atoms, reward, terminated, log_prob), 0.3, 0.97, k, discount.to(GPU)
    )
    assert torch.allclose(gpu.cpu(), cpu, rtol=0, atol=1e-12)


@pytest.mark.parametrize("lowest", [None, 3, 11])
def test_actor_loss_on_the_gpu_matches_the_reference(lowest):
    gen = torch.Generator().manual_seed(15)
    log_prob = torch.randn(3, dtype=f64, generator=gen).requires_grad_()
    atoms = (torch.randn(3, 3, 4, dtype=f64, generator=gen) * 5).requires_grad_()
    if lowest is None:
        want = ref_actor_loss(log_prob, atoms, 0.7)
    else:
        want = ref_actor_cvar_loss(log_prob, atoms, 0.7, lowest)
    g_want = torch.autograd.grad(want, (log_prob, atoms))
    gpu_log_prob, gpu_atoms = on_gpu(log_prob, atoms)
    got = actor_loss(gpu_log_prob, gpu_atoms, 0.7, lowest)
    g_got = torch.autograd.grad(got, (gpu_log_prob, gpu_atoms))
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    for a, b in zip(g_got, g_want, strict=True):
        assert torch.allclose(a.cpu(), b, rtol=1e-12, atol=1e-15)


def test_smoothness_loss_on_the_gpu_matches_the_reference():
    from bipedal_cli.smoothness import smoothness_loss

    from .reference import ref_smoothness_loss

    gen = torch.Generator().manual_seed(16)
    action, jittered = (torch.randn(5, 4, dtype=f64, generator=gen) for _ in range(2))
    action.requires_grad_()
    want = ref_smoothness_loss(action, jittered)
    (g_want,) = torch.autograd.grad(want, action)
    gpu_action, gpu_jittered = on_gpu(action, jittered)
    got = smoothness_loss(gpu_action, gpu_jittered)
    (g_got,) = torch.autograd.grad(got, gpu_action)
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    assert torch.allclose(g_got.cpu(), g_want, rtol=1e-12, atol=1e-15)


def on_cuda(total_steps: int, agent: dict = FEATURES) -> dict:
    data = featured(agent, total_steps=total_steps)
    data["device"] = GPU
    data["agent"].update({"actor_cvar": 0.25, "actor_cvar_start": 150})
    data["agent"].update(  # and every feature that draws noise or changes a target from a step
        {
            "actor_smooth": 0.5,
            "actor_smooth_start": 150,
            "drop_per_critic_final": 2,
            "drop_per_critic_start": 150,
            "target_entropy_final": -6.0,
            "target_entropy_decay_start": 150,
            "target_entropy_decay_end": 300,
        }
    )
    return data


def without_path(state: dict) -> dict:
    return {k: v for k, v in state.items() if k != "path"}


@pytest.mark.parametrize("agent", [FEATURES, LSTM], ids=["flat", "lstm"])
def test_a_cuda_run_repeats_and_resumes_to_the_bit(tmp_path, agent):
    """Same seed, same GPU: the same run; stopped at 230 and resumed, the run not stopped. With
    an LSTM encoder too: cuDNN's LSTM is one of the kernels where that can fail."""
    first = train(config_from_dict(on_cuda(400, agent)), tmp_path / "first")
    again = train(config_from_dict(on_cuda(400, agent)), tmp_path / "again")
    train(config_from_dict(on_cuda(230, agent)), tmp_path / "split")
    resumed = resume(tmp_path / "split", total_steps=400)
    assert first.episodes == again.episodes == resumed.episodes >= 2
    states = {n: load_checkpoint(tmp_path / n / "state.pt") for n in ("first", "again", "split")}
    assert states["first"]["config"]["device"] == "cuda"
    assert states["first"]["rng"]["cuda"] is not None
    assert_states_equal(without_path(states["first"]), without_path(states["again"]))
    assert_states_equal(without_path(states["first"]), without_path(states["split"]))
