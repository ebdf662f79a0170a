"""Replay curation (train.replay_keep_below, FORK's): a curated episode's transitions wait for its
end and enter the buffer only if it fell or scored below the threshold; resume stays exact."""

import numpy as np
import pytest

from bipedal_cli.buffer import ReplayBuffer
from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.episodes import EpisodeRunner
from bipedal_cli.resume import resume
from bipedal_cli.train import train

from .conftest import stats_text
from .test_hardcore_features import featured
from .test_train import assert_states_equal


class ScriptedEnv:
    """An episode of ``length`` steps, reward 1 each; the last one falls if ``fall``."""

    def __init__(self, length: int, fall: bool):
        self.length, self.fall, self.t = length, fall, 0

    def reset(self, seed=None):
        self.t = 0
        return np.full(3, float(seed), np.float32), {}

    def step(self, action):
        self.t += 1
        end = self.t == self.length
        obs = np.full(3, float(self.t), np.float32)
        info = {"fell": end and self.fall, "env_reward": 1.0, "env_steps": 1}
        return obs, 1.0, end and self.fall, end and not self.fall, info

    def close(self):
        pass


def runner_with(episodes, n_step=1, keep_below=5.0):
    """A runner whose successive envs play ``episodes`` ((length, fall) each)."""
    data = featured()
    data["agent"]["n_step"] = n_step
    data["train"]["replay_keep_below"] = keep_below
    cfg = config_from_dict(data)
    buffer = ReplayBuffer(100, 3, 4, with_discount=n_step > 1)
    scripted = iter([ScriptedEnv(*e) for e in [(1, False), *episodes]])  # the first: __init__'s
    runner = EpisodeRunner.__new__(EpisodeRunner)
    runner.cfg, runner.buffer = cfg, buffer
    runner.nstep = None
    if n_step > 1:
        from bipedal_cli.nstep import NStepAccumulator

        runner.nstep = NStepAccumulator(n_step, cfg.agent.gamma)
    runner._make_env = lambda: next(scripted)
    runner.env = runner._make_env()
    runner.staged, runner.obs = [], None
    return runner, buffer


def play(runner, seed, curated):
    runner.start(seed, curated, None)
    while (done := runner.step(np.zeros(4, np.float32))) is None:
        pass
    return done


@pytest.mark.parametrize("n_step", [1, 3])
def test_only_failed_or_low_scoring_curated_episodes_are_stored(n_step):
    runner, buffer = runner_with([(8, False), (6, True), (3, False), (9, False)], n_step)
    high = play(runner, 1, curated=True)  # return 8 >= 5, no fall: dropped
    assert (high.stored, high.env_ret, len(buffer)) == (False, 8.0, 0)
    fell = play(runner, 2, curated=True)  # a fall: kept, whatever its return
    assert fell.stored and len(buffer) == 6
    ends = min(n_step, 6)  # the transitions whose n steps reach the fall
    assert buffer.terminated[:6].tolist() == [0.0] * (6 - ends) + [1.0] * ends
    low = play(runner, 3, curated=True)  # return 3 < 5: kept
    assert low.stored and len(buffer) == 9
    plain = play(runner, 4, curated=False)  # not curated: every step stored as it comes
    assert plain.stored and len(buffer) == 18
    assert runner.staged == []


def test_replay_restages_a_curated_episode_cut_by_a_checkpoint():
    runner, buffer = runner_with([(8, True), (8, True)], n_step=3)
    runner.start(7, True, None)
    actions = [np.full(4, i / 10, np.float32) for i in range(5)]
    for a in actions:
        runner.step(a)
    staged, obs = runner.staged, runner.obs
    assert len(staged) == 3 and len(buffer) == 0  # 5 steps, 2 still pending in the n-step queue
    assert runner.replay(7, np.array(actions), obs, True, None)
    assert len(runner.staged) == len(staged) and len(buffer) == 0
    for a, b in zip(runner.staged, staged, strict=True):
        assert all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def curated(**train_keys):
    data = featured(**train_keys)
    data["train"].update(replay_keep_below=-20.0, replay_curation_start=120)
    return data


def test_resume_is_exact_with_curation_and_it_changes_the_run(tmp_path):
    straight = train(config_from_dict(curated(total_steps=400)), tmp_path / "straight")
    train(config_from_dict(curated(total_steps=230)), tmp_path / "split")
    cut = load_checkpoint(tmp_path / "split" / "state.pt")["episode"]
    assert cut["curated"] and len(cut["actions"]) > 0  # the checkpoint cuts a curated episode
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes >= 2
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in a.items() if k != "path"}, {k: v for k, v in b.items() if k != "path"}
    )
    train(config_from_dict(featured(total_steps=400)), tmp_path / "plain")
    plain = load_checkpoint(tmp_path / "plain" / "state.pt")
    assert not np.array_equal(plain["buffer"]["obs"].numpy(), a["buffer"]["obs"].numpy())


def test_the_display_shows_the_share_of_recent_episodes_the_curation_kept():
    from bipedal_cli.snapshot import replay_kept_share

    returns, falls = [300.0, 100.0, 280.0, 290.0], [False, False, True, False]
    assert replay_kept_share(returns, falls, 250.0) == 0.5  # the low one and the fall
    assert replay_kept_share(returns, falls, None) is None
    assert replay_kept_share([], [], 250.0) is None
    assert "replay kept  50%" in stats_text({"step": 10, "replay_kept": 0.5})
    assert "replay kept" not in stats_text({"step": 10, "replay_kept": None})


def test_the_snapshot_reports_the_kept_share_once_curation_has_started():
    from types import SimpleNamespace

    from bipedal_cli.config import Config
    from bipedal_cli.snapshot import training_snapshot

    cfg = Config()
    cfg.train.replay_keep_below, cfg.train.replay_curation_start = 250.0, 500
    trainer = SimpleNamespace(
        cfg=cfg,
        step=499,
        episodes=3,
        wall_time=1.0,
        recent_returns=[300.0, 100.0, 290.0],
        recent_falls=[False, False, True],
        last_eval=None,
        last_metrics={},
        agent=SimpleNamespace(learning_rate=lambda: 7.3e-4),
    )
    assert training_snapshot(trainer, 0.0)["replay_kept"] is None  # before its start
    trainer.step = 500
    assert training_snapshot(trainer, 0.0)["replay_kept"] == pytest.approx(2 / 3)
    cfg.train.replay_keep_below = None
    assert training_snapshot(trainer, 0.0)["replay_kept"] is None
