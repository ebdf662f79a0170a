"""The TQC update: every gradient at the same parameters, and the two-thread split exact."""

import copy
import dataclasses

import pytest
import torch

from bipedal_cli.agent import TQCAgent
from bipedal_cli.config import AgentConfig
from bipedal_cli.losses import actor_loss, quantile_huber_loss, truncated_target

OBS, ACT = 6, 2
SMALL = AgentConfig(
    batch_size=8,
    n_critics=3,
    n_quantiles=5,
    drop_per_critic=1,
    actor_hidden=16,
    critic_hidden=12,
)


# the same with an LSTM over a window of 3 observations of 2 floats (encoders.py)
SMALL_LSTM = dataclasses.replace(SMALL, history=3, encoder="lstm", encoder_hidden=4)


def make_agent(worker: bool, cfg: AgentConfig = SMALL) -> TQCAgent:
    torch.manual_seed(0)
    agent = TQCAgent(cfg, OBS, ACT)
    agent.noise.manual_seed(1)
    if worker:
        agent.start_worker()
    return agent


def make_batch(seed: int, act_dim: int = ACT) -> dict[str, torch.Tensor]:
    gen = torch.Generator().manual_seed(seed)
    B = SMALL.batch_size
    return {
        "obs": torch.randn(B, OBS, generator=gen),
        "action": torch.rand(B, act_dim, generator=gen) * 2 - 1,
        "reward": torch.randn(B, generator=gen),
        "next_obs": torch.randn(B, OBS, generator=gen),
        "terminated": (torch.rand(B, generator=gen) < 0.2).float(),
    }


@pytest.mark.parametrize("cfg", [SMALL, SMALL_LSTM], ids=["flat", "lstm"])
def test_update_on_a_worker_thread_is_bit_identical_to_one_thread(cfg):
    torch.set_num_threads(1)
    plain, split = make_agent(worker=False, cfg=cfg), make_agent(worker=True, cfg=cfg)
    try:
        for i in range(25):
            batch = make_batch(i)
            m_plain, m_split = plain.update(batch), split.update(batch)
            assert m_plain.keys() == m_split.keys()
            assert all(torch.equal(m_plain[k], m_split[k]) for k in m_plain)
    finally:
        split.stop_worker()
    a, b = plain.state_dict(), split.state_dict()
    for net in ("actor", "critic", "critic_target"):
        assert all(torch.equal(a[net][k], b[net][k]) for k in a[net]), net
    assert torch.equal(a["log_alpha"], b["log_alpha"])
    assert torch.equal(a["noise_rng"], b["noise_rng"])
    for opt in ("actor_opt", "critic_opt"):
        for key, state in a[opt]["state"].items():
            for name, value in state.items():
                assert torch.equal(value, b[opt]["state"][key][name]), (opt, name)


@pytest.mark.parametrize("cfg", [SMALL, SMALL_LSTM], ids=["flat", "lstm"])
@pytest.mark.parametrize("worker", [False, True])
def test_all_gradients_are_taken_at_the_parameters_before_the_update(worker, cfg):
    """The paper's algorithm: grad J_Z, grad J_pi and grad J(alpha) all at (psi, phi, alpha)."""
    torch.set_num_threads(1)
    agent = make_agent(worker, cfg)
    for i in range(3):  # move away from the initial parameters (Adam state included)
        agent.update(make_batch(100 + i))
    before = copy.deepcopy(agent.state_dict())
    batch = make_batch(7)
    noise = torch.Generator().set_state(agent.noise.get_state())  # the update's next draw
    eps = torch.randn((2, SMALL.batch_size, ACT), generator=noise)
    try:
        agent.update(batch)
    finally:
        agent.stop_worker()

    # The same gradients from a copy holding the parameters before the update.
    ref = make_agent(worker=False, cfg=cfg)
    ref.load_state_dict(before)
    alpha = ref.log_alpha.detach().exp()
    with torch.no_grad():
        next_action, next_log_prob = ref.actor.sample(batch["next_obs"], eps=eps[1])
        target = truncated_target(
            ref.critic_target(batch["next_obs"], next_action),
            batch["reward"],
            batch["terminated"],
            next_log_prob,
            alpha,
            SMALL.gamma,
            SMALL.drop_per_critic,
        )
    critic_grads = torch.autograd.grad(
        quantile_huber_loss(ref.critic(batch["obs"], batch["action"]), target),
        list(ref.critic.parameters()),
    )
    action, log_prob = ref.actor.sample(batch["obs"], eps=eps[0])
    actor_grads = torch.autograd.grad(
        actor_loss(log_prob, ref.critic(batch["obs"], action), alpha),
        list(ref.actor.parameters()),
    )
    for got, want in zip(agent.critic.parameters(), critic_grads, strict=True):
        torch.testing.assert_close(got.grad, want, rtol=1e-5, atol=1e-7)
    for got, want in zip(agent.actor.parameters(), actor_grads, strict=True):
        torch.testing.assert_close(got.grad, want, rtol=1e-5, atol=1e-7)
    # ... and every parameter moved after its gradient was taken.
    assert not torch.equal(agent.log_alpha.detach(), before["log_alpha"])
    assert not torch.equal(agent.critic.state_dict()["net.w_out"], before["critic"]["net.w_out"])


def test_an_error_on_the_worker_thread_reaches_the_caller():
    agent = make_agent(worker=True)
    try:
        with pytest.raises(RuntimeError):  # by the next call that waits for the worker
            agent.update(make_batch(0, act_dim=ACT + 1))  # the critics' part fails on a shape
            agent.sync()
        metrics = agent.update(make_batch(1))  # the worker is still usable afterwards
        assert torch.isfinite(metrics["critic_loss"])
    finally:
        agent.stop_worker()
