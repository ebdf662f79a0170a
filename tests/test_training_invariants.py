"""Bugs that would quietly ruin training, each pinned by a value (issue 16): the target critics'
Polyak step, what the loop stores at a time-limit truncation, evaluation's deterministic action,
the optimizers' round trip."""

import gymnasium as gym
import numpy as np
import pytest
import torch

from bipedal_cli.agent import TQCAgent
from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.envs import RewardShaping, make_env
from bipedal_cli.evaluation import evaluate_actor
from bipedal_cli.train import Trainer, train
from bipedal_cli.training_loop import WallClock, env_step

from .conftest import tiny_dict


def random_batch(B, gen):
    return {
        "obs": torch.randn(B, 24, generator=gen),
        "action": torch.rand(B, 4, generator=gen) * 2 - 1,
        "reward": torch.randn(B, generator=gen),
        "next_obs": torch.randn(B, 24, generator=gen),
        "terminated": (torch.rand(B, generator=gen) < 0.2).float(),
    }


@pytest.mark.parametrize("tau", [0.005, 0.25])
def test_target_critics_move_by_exactly_tau_towards_the_updated_critics(tau):
    """psi_bar <- psi_bar + tau (psi - psi_bar), with psi after its Adam step."""
    cfg = config_from_dict(tiny_dict()).agent
    cfg.tau = tau
    torch.manual_seed(0)
    agent = TQCAgent(cfg, 24, 4)
    with torch.no_grad():  # start the targets well away from the critics
        for p in agent.critic_target.parameters():
            p.add_(torch.randn_like(p) * 0.1)
    before = [p.detach().clone().double() for p in agent.critic_target.parameters()]
    agent.update(random_batch(16, torch.Generator().manual_seed(1)))
    agent.sync()
    online = [p.detach().double() for p in agent.critic.parameters()]
    for old, new, psi in zip(before, agent.critic_target.parameters(), online, strict=True):
        expected = old + tau * (psi - old)
        assert torch.allclose(new.double(), expected, rtol=0, atol=1e-7)
        assert (new.double() - old).abs().max() > 1e-4  # it moved (no skipped update)


class FakeWalker(gym.Env):
    """24 observations, 4 actions; an episode whose seed is even falls (-100) at step 6, an odd
    one walks until the time limit cuts it."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (24,), np.float32)
    action_space = gym.spaces.Box(-1, 1, (4,), np.float32)
    metadata = {"render_fps": 50}

    def reset(self, seed=None, options=None):
        self.t, self.falls = 0, seed is not None and seed % 2 == 0
        return np.full(24, float(seed % 1000), np.float32), {}

    def step(self, action):
        self.t += 1
        fell = self.falls and self.t == 6
        return np.full(24, self.t, np.float32), -100.0 if fell else 1.0, fell, False, {}


def test_the_loop_stores_terminated_only_at_falls_never_at_time_limits(monkeypatch):
    """The paper's bug: storing `terminated or truncated` cuts the bootstrap at time limits."""
    steps_seen = []

    def fake_make_env(env_id, render=False, **kwargs):
        env = RewardShaping(gym.wrappers.TimeLimit(FakeWalker(), max_episode_steps=10))

        class Recorder(gym.Wrapper):
            def step(self, action):
                out = self.env.step(action)
                steps_seen.append((out[2], out[3]))  # terminated, truncated
                return out

        return Recorder(env)

    monkeypatch.setattr("bipedal_cli.episodes.make_env", fake_make_env)
    trainer = Trainer(config_from_dict(tiny_dict(total_steps=120, warmup_steps=200)), "unused")
    trainer.start_episode()
    for _ in range(120):
        env_step(trainer, _NoMetrics(), WallClock(0.0))
    stored = trainer.buffer.terminated[: len(steps_seen)].tolist()
    assert len(steps_seen) == 120 == len(trainer.buffer)
    assert stored == [float(term) for term, _ in steps_seen]
    assert sum(trunc for _, trunc in steps_seen) >= 3  # time limits reached ...
    assert sum(term for term, _ in steps_seen) >= 3  # ... and falls
    assert all(s == 0.0 for s, (_, trunc) in zip(stored, steps_seen, strict=True) if trunc)


class _NoMetrics:
    def write(self, row):
        pass


def hand_rollout(actor, env_id, seed):
    """The deterministic policy tanh(mu(s)) played by hand, with mu read off the network."""
    env = make_env(env_id)
    obs, _ = env.reset(seed=seed)
    ret, done = 0.0, False
    while not done:
        with torch.no_grad():
            out = actor.net(torch.as_tensor(obs[None]))[:, 0]  # (1, 2A): mean, log std
            action = torch.tanh(out[:, :4])[0].numpy()
        obs, r, term, trunc, _ = env.step(action)
        ret, done = ret + float(r), term or trunc
    return ret


def test_every_evaluation_path_plays_the_deterministic_policy_exactly(tmp_path):
    result = train(config_from_dict(tiny_dict(total_steps=300)), tmp_path / "run")
    state = load_checkpoint(result.run_dir / "state.pt")
    trainer = Trainer(config_from_dict(state["config"]), tmp_path / "other")
    trainer.load_state_dict(state)
    actor = trainer.agent.actor
    seeds = [11, 12]
    want = [hand_rollout(actor, "BipedalWalker-v3", s) for s in seeds]
    # one episode per batch in every path: a batch of 2 may round the products differently
    agent_cfg, env_id = trainer.cfg.agent, trainer.cfg.env
    in_process = evaluate_actor(actor, agent_cfg, env_id, seeds, workers=1, chunk=1)
    workers = evaluate_actor(actor, agent_cfg, env_id, seeds, workers=2, chunk=1)
    periodic = []
    for s in seeds:
        trainer.cfg.train.eval_seed = s
        periodic.append(trainer.evaluate(1)["mean"])
    assert [r.ret for r in in_process] == want
    assert [r.ret for r in workers] == want
    assert periodic == want


def test_restored_optimizers_hold_the_saved_moments(tmp_path):
    result = train(config_from_dict(tiny_dict(total_steps=200)), tmp_path / "run")
    state = load_checkpoint(result.run_dir / "state.pt")
    trainer = Trainer(config_from_dict(state["config"]), tmp_path / "other")
    trainer.load_state_dict(state)
    for name in ("actor_opt", "critic_opt", "alpha_opt"):
        saved = state["agent"][name]["state"]
        restored = getattr(trainer.agent, name).state_dict()["state"]
        assert saved and restored.keys() == saved.keys(), name
        for index, moments in saved.items():
            for key in ("step", "exp_avg", "exp_avg_sq"):
                assert torch.equal(restored[index][key], moments[key]), (name, index, key)


def test_best_policy_is_the_actor_at_the_best_evaluation_of_its_env(tmp_path, monkeypatch):
    """best_policy.pt holds the actor as it was at the highest periodic evaluation so far; a
    policy file of another env (a curriculum's earlier stage) or an unreadable one is replaced."""
    from bipedal_cli.checkpoint import BEST_POLICY_FILE, recorded_evaluation

    means = iter([10.0, 50.0, 30.0, 50.0])  # the tie at the end keeps the earlier actor
    seen = {}

    def fake_evaluate(self, episodes):
        mean = next(means)
        seen[self.step] = {k: v.clone() for k, v in self.agent.actor.state_dict().items()}
        return {"episodes": 20, "mean": mean, "std": 0.0, "mean_length": 1.0, "falls": 0}

    monkeypatch.setattr(Trainer, "evaluate", fake_evaluate)
    cfg = config_from_dict(tiny_dict(eval_every=100, warmup_steps=50, total_steps=400))
    run = tmp_path / "run"
    run.mkdir()
    (run / BEST_POLICY_FILE).write_bytes(b"not a checkpoint")
    train(cfg, run)
    best = load_checkpoint(run / BEST_POLICY_FILE)
    assert best["meta"]["last_eval"]["mean"] == 50.0 and best["meta"]["steps"] == 200
    for key, value in seen[200].items():
        assert torch.equal(best["actor"][key], value), key
    assert any(not torch.equal(best["actor"][k], v) for k, v in seen[400].items())  # it learned
    assert recorded_evaluation(run / BEST_POLICY_FILE, cfg.env) == 50.0
    assert recorded_evaluation(run / BEST_POLICY_FILE, "BipedalWalkerHardcore-v3") is None
