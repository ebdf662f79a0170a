"""The actor's smoothness term (agent.actor_smooth, CAPS's spatial term) against a plain float64
reference, values and gradients, and inside the agent's update."""

import pytest
import torch

from bipedal_cli.config import config_from_dict
from bipedal_cli.networks import make_actor
from bipedal_cli.smoothness import smoothness_loss, smoothness_penalty

from .conftest import tiny_dict
from .reference import ref_smoothness_loss


def test_smoothness_loss_matches_reference_value_and_gradient():
    gen = torch.Generator().manual_seed(21)
    action, jittered = (
        torch.rand(6, 4, dtype=torch.float64, generator=gen).mul(2).sub(1).requires_grad_()
        for _ in range(2)
    )
    got, want = smoothness_loss(action, jittered), ref_smoothness_loss(action, jittered)
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    g_got = torch.autograd.grad(got, (action, jittered))
    g_want = torch.autograd.grad(want, (action, jittered))
    for a, b in zip(g_got, g_want, strict=True):
        assert torch.allclose(a, b, rtol=1e-12, atol=0)
    # d/d mu(s) of ||mu(s) - mu(s~)|| / B is the unit vector from mu(s~) to mu(s), over B
    diff = (action - jittered).detach()
    assert torch.allclose(g_got[0], diff / diff.norm(dim=1, keepdim=True) / 6, rtol=1e-12)
    assert torch.equal(g_got[1], -g_got[0])


def test_equal_actions_cost_nothing_and_give_a_zero_gradient():
    action = torch.zeros(3, 4, dtype=torch.float64, requires_grad=True)
    loss = smoothness_loss(action, action.detach().clone())
    (grad,) = torch.autograd.grad(loss, action)
    assert loss.item() == 0.0 and torch.equal(grad, torch.zeros_like(grad))


def test_penalty_is_the_weighted_loss_at_jittered_states_drawn_from_the_generator():
    cfg = config_from_dict(tiny_dict()).agent
    actor = make_actor(cfg, 24, 4).double()
    obs = torch.randn(5, 24, dtype=torch.float64, generator=torch.Generator().manual_seed(3))
    noise = torch.Generator().manual_seed(4)
    replay = torch.Generator().manual_seed(4)
    got = smoothness_penalty(actor, obs, actor.distribution_params(obs)[0], noise, 0.7, 0.05)
    xi = torch.randn(obs.shape, generator=replay, dtype=torch.float64)
    want = 0.7 * ref_smoothness_loss(actor.deterministic(obs), actor.deterministic(obs + 0.05 * xi))
    assert got.item() == pytest.approx(want.item(), rel=1e-12)
    params = list(actor.parameters())
    for a, b in zip(
        torch.autograd.grad(got, params), torch.autograd.grad(want, params), strict=True
    ):
        assert torch.allclose(a, b, rtol=1e-9, atol=1e-15)
    # the generator moved by one draw of the batch's shape: the next call jitters anew
    assert torch.equal(noise.get_state(), replay.get_state())


def test_the_penalty_from_the_samples_own_forward_pass_is_the_one_on_2b_states():
    """Eq. 2's sample gives mu(s) (``sample_with_mean``); the term built on it has the value
    and gradient of the term that ran the actor on [s; s~] itself (session 49's)."""
    cfg = config_from_dict(tiny_dict()).agent
    torch.manual_seed(10)
    actor = make_actor(cfg, 24, 4)
    obs = torch.randn(32, 24, generator=torch.Generator().manual_seed(11))
    eps = torch.randn(32, 4, generator=torch.Generator().manual_seed(12))
    action, log_prob, mean = actor.sample_with_mean(obs, eps=eps)
    sampled_action, sampled_log_prob = actor.sample(obs, eps=eps)
    assert torch.equal(action, sampled_action) and torch.equal(log_prob, sampled_log_prob)
    assert torch.equal(torch.tanh(mean), actor.deterministic(obs))
    got = smoothness_penalty(actor, obs, mean, torch.Generator().manual_seed(13), 2.0, 0.01)
    xi = torch.randn(obs.shape, generator=torch.Generator().manual_seed(13))
    both = actor.deterministic(torch.cat([obs, obs + 0.01 * xi]))  # (2B, A)
    want = 2.0 * smoothness_loss(*both.chunk(2))
    assert got.item() == pytest.approx(want.item(), rel=1e-5)
    params = list(actor.parameters())
    for a, b in zip(
        torch.autograd.grad(got, params), torch.autograd.grad(want, params), strict=True
    ):
        assert torch.allclose(a, b, rtol=1e-4, atol=1e-6)


def test_the_update_adds_the_term_to_the_actors_loss_only_once_it_is_on():
    from bipedal_cli.agent import TQCAgent

    data = tiny_dict()
    data["agent"].update(actor_smooth=5.0, actor_smooth_sigma=0.1)
    cfg = config_from_dict(data).agent
    gen = torch.Generator().manual_seed(5)
    batch = {
        "obs": torch.randn(8, 24, generator=gen),
        "action": torch.rand(8, 4, generator=gen) * 2 - 1,
        "reward": torch.randn(8, generator=gen),
        "next_obs": torch.randn(8, 24, generator=gen),
        "terminated": torch.zeros(8),
    }
    losses = {}
    for on in (None, 5.0):
        torch.manual_seed(0)
        agent = TQCAgent(cfg, 24, 4)
        agent.actor_smooth = on
        losses[on] = agent.update(batch)["actor_loss"].item()
    # the same eq. 2 at the same parameters and noise, plus a positive penalty
    assert losses[5.0] > losses[None]


def test_descending_the_penalty_makes_the_actor_less_sensitive_to_a_jitter():
    cfg = config_from_dict(tiny_dict()).agent
    torch.manual_seed(6)
    actor = make_actor(cfg, 24, 4)
    obs = torch.randn(64, 24, generator=torch.Generator().manual_seed(7))
    probe = torch.Generator().manual_seed(8)

    def sensitivity() -> float:
        with torch.no_grad():
            xi = torch.randn(obs.shape, generator=probe.manual_seed(8))
            moved = actor.deterministic(obs) - actor.deterministic(obs + 0.1 * xi)
            return moved.norm(dim=1).mean().item()

    before = sensitivity()
    opt = torch.optim.Adam(actor.parameters(), lr=1e-2)
    noise = torch.Generator().manual_seed(9)
    for _ in range(50):
        opt.zero_grad()
        smoothness_penalty(
            actor, obs, actor.distribution_params(obs)[0], noise, 1.0, 0.1
        ).backward()
        opt.step()
    assert sensitivity() < 0.5 * before
