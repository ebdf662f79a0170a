"""Adam's moments left out of a restart file and estimated again after its refill
(:mod:`bipedal_cli.adam_moments`): steps of size zero move no weight, take the same gradients as
an update, and run only in a run restarted from a file without moments."""

import shutil

import numpy as np
import torch

from bipedal_cli import scheduled_update
from bipedal_cli.adam_moments import (
    accumulate_moments,
    estimate_moments,
    moment_batches,
    moments_missing,
    step_moments_only,
    without_moments,
)
from bipedal_cli.agent import TQCAgent
from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.resume import branch
from bipedal_cli.train import Trainer, train

from .conftest import tiny_dict


def a_batch(agent: TQCAgent, size: int = 16) -> dict[str, torch.Tensor]:
    rng = np.random.default_rng(0)
    obs_dim, act_dim = agent.obs_dim, agent.act_dim
    return agent.batch_to_tensors(
        {
            "obs": rng.normal(size=(size, obs_dim)).astype(np.float32),
            "action": rng.uniform(-1, 1, (size, act_dim)).astype(np.float32),
            "reward": rng.normal(size=size).astype(np.float32),
            "next_obs": rng.normal(size=(size, obs_dim)).astype(np.float32),
            "terminated": (rng.uniform(size=size) < 0.2).astype(np.float32),
        }
    )


def weights(agent: TQCAgent) -> list[torch.Tensor]:
    nets = (agent.actor, agent.critic, agent.critic_target)
    return [p.detach().clone() for net in nets for p in net.parameters()] + [
        agent.log_alpha.detach().clone()
    ]


def test_a_step_of_size_zero_moves_no_weight_and_keeps_the_learning_rate():
    p = torch.nn.Parameter(torch.tensor([1.0, -2.0]))
    opt = torch.optim.Adam([p], lr=0.1, fused=True)
    p.grad = torch.tensor([0.5, -3.0])
    step_moments_only(opt)
    assert torch.equal(p.detach(), torch.tensor([1.0, -2.0]))
    assert opt.param_groups[0]["lr"] == 0.1
    moments = opt.state[p]
    assert torch.allclose(moments["exp_avg"], 0.1 * p.grad)  # (1 - b1) g
    assert torch.allclose(moments["exp_avg_sq"], 0.001 * p.grad**2)  # (1 - b2) g^2


def test_accumulated_moments_are_the_gradients_of_an_update_at_fixed_weights():
    cfg = config_from_dict(tiny_dict()).agent
    agent = TQCAgent(cfg, 24, 4)
    batch = a_batch(agent)
    before = weights(agent)
    noise = agent.noise.get_state()
    accumulate_moments(agent, batch)
    assert all(torch.equal(a, b) for a, b in zip(before, weights(agent), strict=True))
    assert not moments_missing(agent) and not agent.alpha_opt.state  # the temperature waits
    # the same gradients by hand: the noise the update would draw, both losses, no step
    reference = TQCAgent(cfg, 24, 4)
    reference.actor.load_state_dict(agent.actor.state_dict())
    reference.critic.load_state_dict(agent.critic.state_dict())
    reference.critic_target.load_state_dict(agent.critic_target.state_dict())
    reference.noise.set_state(noise)
    eps = torch.randn((2, 16, 4), generator=reference.noise)
    alpha = reference.log_alpha.detach().exp()
    reference.critic_gradients(batch, eps[1], alpha)
    reference.actor_gradients(batch["obs"], eps[0], alpha)
    for net, opt in ((reference.critic, agent.critic_opt), (reference.actor, agent.actor_opt)):
        for p_ref, p in zip(net.parameters(), opt.param_groups[0]["params"], strict=True):
            g = p_ref.grad
            torch.testing.assert_close(opt.state[p]["exp_avg_sq"], (1 - 0.999) * g * g)
            torch.testing.assert_close(opt.state[p]["exp_avg"], (1 - 0.9) * g)


def test_estimate_takes_k_batches_of_the_buffer_and_moves_no_weight(tmp_path):
    cfg = config_from_dict(tiny_dict(total_steps=150))
    train(cfg, tmp_path / "run")
    trainer = Trainer(cfg, tmp_path / "again")
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    state["agent"] = without_moments(state["agent"])
    trainer.load_state_dict(state)
    assert moments_missing(trainer.agent)
    before, rng_before = weights(trainer.agent), trainer.rng.bit_generator.state
    assert estimate_moments(trainer, 16) == moment_batches(trainer.agent.critic_opt) == 1000
    assert all(torch.equal(a, b) for a, b in zip(before, weights(trainer.agent), strict=True))
    assert trainer.rng.bit_generator.state != rng_before  # batches drawn with the run's generator
    counts = {float(s["step"]) for s in trainer.agent.critic_opt.state.values()}
    assert counts == {1000.0} and not moments_missing(trainer.agent)


def test_an_older_restart_file_with_moments_restarts_without_an_estimate(tmp_path, monkeypatch):
    train(config_from_dict(tiny_dict(total_steps=230)), tmp_path / "run")
    # a restart file as written before 2026-12-05: with the moments, and the metrics as text
    state = load_checkpoint(tmp_path / "run" / "restart.pt")
    full = load_checkpoint(tmp_path / "run" / "state.pt")
    state.pop("path")
    state["agent"] = full["agent"]
    state["restart"] = {"step": 230, "metrics_csv": (tmp_path / "run" / "metrics.csv").read_text()}
    torch.save(state, tmp_path / "old-restart.pt")
    calls = []
    monkeypatch.setattr(scheduled_update, "estimate_moments", lambda *a: calls.append(a))
    explicit = {"train.refill_steps": 60, "train.total_steps": 400}
    branch(tmp_path / "old-restart.pt", tmp_path / "old", explicit=explicit)
    assert calls == []
    shutil.copyfile(tmp_path / "run" / "restart.pt", tmp_path / "new-restart.pt")
    branch(tmp_path / "new-restart.pt", tmp_path / "new", explicit=explicit)
    assert len(calls) == 1  # at the first learning step after the refill, once


def test_the_benchmarks_recent_buffer_is_the_last_transitions_in_order():
    from bipedal_cli.buffer import ReplayBuffer

    from .conftest import load_benchmark

    recent_buffer = load_benchmark("restart_moments").recent_buffer
    buffer = ReplayBuffer(5, 1, 1)
    for i in range(3):  # not full: slots 0-2
        buffer.add([i], [0.0], float(i), [i + 1], False)
    assert recent_buffer(buffer, 2).reward.tolist() == [1.0, 2.0]
    for i in range(3, 8):  # wrapped: slots hold 5, 6, 7, 3, 4 and the next write is slot 3
        buffer.add([i], [0.0], float(i), [i + 1], False)
    recent = recent_buffer(buffer, 4)
    assert recent.reward.tolist() == [4.0, 5.0, 6.0, 7.0] and len(recent) == 4
    assert recent_buffer(buffer, 10).reward.tolist() == [3.0, 4.0, 5.0, 6.0, 7.0]
