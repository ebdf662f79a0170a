"""Restarts near recent falls (train.fall_restart): the draw, the exact rebuild of the state before
a fall with nothing stored twice, the cut at the horizon (a truncation that bootstraps), the run
that is the plain run to the bit before its start and resumes exactly inside a restart, the
branch rule, the key errors and the display."""

import re

import numpy as np
import pytest
import torch

from bipedal_cli.buffer import ReplayBuffer
from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.envs import policy_dims
from bipedal_cli.episodes import EpisodeRunner
from bipedal_cli.errors import UserError
from bipedal_cli.fall_restarts import FallMemory, restart_length, restarts_on
from bipedal_cli.metrics import read_metrics
from bipedal_cli.resume import branch, resume
from bipedal_cli.train import Trainer, train

from .conftest import stats_text, tiny_dict
from .test_train import assert_states_equal

RESTARTS = {
    "fall_restart": 0.7,
    "fall_restart_back": 10,
    "fall_restart_horizon": 20,
    "fall_restart_start": 50,
}


def restart_dict(total_steps: int, **train_keys) -> dict:
    return tiny_dict(total_steps=total_steps, **{**RESTARTS, **train_keys})


def assert_resumed_split_equals_straight(tmp_path, straight, rows):
    """tmp_path/split, stopped mid-episode, resumed to 400 policy steps: the same episodes, state
    and metrics (but wall times) as tmp_path/straight, which ran there in one go."""
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes
    s, r = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in s.items() if k != "path"}, {k: v for k, v in r.items() if k != "path"}
    )
    timeless = [{k: v for k, v in row.items() if k != "wall_time"} for row in rows]
    resumed = read_metrics(tmp_path / "split" / "metrics.csv")
    assert [{k: v for k, v in row.items() if k != "wall_time"} for row in resumed] == timeless


def test_the_draw_follows_the_probability_the_back_off_and_the_memory():
    t = config_from_dict(restart_dict(400, fall_restart=1.0, fall_restart_back=3)).train
    assert restarts_on(t, 51) and not restarts_on(t, 50)
    assert not restarts_on(config_from_dict(tiny_dict()).train, 10**6)
    assert [restart_length(10, b) for b in (1, 3, 12)] == [9, 7, 0]
    memory, rng = FallMemory(capacity=2), np.random.default_rng(0)
    before = rng.bit_generator.state
    assert memory.draw(rng, t) is None and rng.bit_generator.state == before  # nothing drawn
    for seed in (5, 6, 7):
        memory.remember(seed, np.full((10, 4), seed, np.float32), act_dim=4)
    assert [s for s, _ in memory.falls] == [6, 7]  # the last two
    draws = [memory.draw(rng, t) for _ in range(300)]
    assert {s for s, _ in draws} == {6, 7}
    assert {len(prefix) for _, prefix in draws} == {7, 8, 9}
    t.fall_restart_back_min = 2
    assert {len(memory.draw(rng, t)[1]) for _ in range(100)} == {7, 8}
    assert all((prefix == seed).all() for seed, prefix in draws)
    t.fall_restart = 0.25
    fresh = sum(memory.draw(rng, t) is None for _ in range(2000))
    assert 1350 < fresh < 1650  # 1500 expected
    again = FallMemory(capacity=2)
    again.load_state_dict(memory.state_dict())
    assert [(s, a.tolist()) for s, a in again.falls] == [(s, a.tolist()) for s, a in memory.falls]


def falling_episode(runner: EpisodeRunner, rng: np.random.Generator, act_dim: int):
    """A fresh episode of random actions that falls: its seed, actions and observations."""
    for seed in range(100):
        runner.start(seed, False, None)
        actions, observations = [], [runner.obs.copy()]
        while True:
            action = rng.uniform(-1, 1, act_dim).astype(np.float32)
            actions.append(action)
            finished = runner.step(action)
            observations.append(runner.obs.copy())
            if finished is not None:
                break
        if finished.fell and len(actions) > 40:
            return seed, np.array(actions), observations, finished
    raise AssertionError("no random episode fell")


@pytest.mark.parametrize("n_step", [1, 3])
def test_a_restart_rebuilds_the_state_before_the_fall_and_is_cut_at_its_horizon(n_step):
    data = restart_dict(400, fall_restart_horizon=5)
    data["agent"]["n_step"] = n_step
    cfg = config_from_dict(data)
    obs_dim, act_dim = policy_dims(cfg.env, cfg.agent)
    runner = EpisodeRunner(cfg, ReplayBuffer(10_000, obs_dim, act_dim, n_step > 1))
    seed, actions, observations, fell = falling_episode(runner, np.random.default_rng(1), act_dim)

    buffer = ReplayBuffer(10_000, obs_dim, act_dim, n_step > 1)
    again = EpisodeRunner(cfg, buffer)
    k = len(actions) - 20
    again.start(seed, False, None, prefix=actions[:k])
    assert np.array_equal(again.obs, observations[k]) and len(buffer) == 0  # nothing stored
    for i in range(k, k + 4):
        assert again.step(actions[i]) is None
    cut = again.step(actions[k + 4])
    assert cut is not None and not cut.fell
    assert cut.restart_env_steps == again.episode.restart_env_steps > 0
    assert len(buffer) == 5 and not buffer.terminated[:5].any()  # a truncation: it bootstraps
    if n_step > 1:
        assert (buffer.discount[:5] > 0).all()

    again.start(seed, False, None, prefix=actions[:k])
    again.episode.restart_at = None  # no horizon: the restart plays to the fall
    for action in actions[k:-1]:
        assert again.step(action) is None
    last = again.step(actions[-1])
    assert last.fell and last.env_ret == pytest.approx(fell.env_ret)  # the same episode


def test_a_run_restarts_near_its_falls_and_books_them_apart(tmp_path):
    trainer = Trainer(config_from_dict(restart_dict(400)), tmp_path / "run")
    trainer.run()
    rows = read_metrics(tmp_path / "run" / "metrics.csv")
    fresh = [r for r in rows if r["kind"] == "episode"]
    restarts = [r for r in rows if r["kind"] == "restart"]
    assert restarts and all(
        0 <= int(r["restart_from"]) < int(r["length"])
        and (r["fell"] == "1" or int(r["length"]) - int(r["restart_from"]) == 20)
        for r in restarts
    )
    assert all(r["restart_from"] == "" for r in fresh)
    assert trainer.episodes == len(rows)
    assert list(trainer.recent_returns) == pytest.approx(
        [float(r["return"]) for r in fresh], abs=1e-3
    )
    fallen = [r for r in fresh if r["fell"] == "1" and int(r["step"]) > 50]
    assert len(trainer.fall_memory) == len(fallen)  # fresh falls only, from the start step


def test_the_run_is_the_plain_run_before_its_start_and_resumes_exactly_inside_a_restart(
    tmp_path,
):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "plain")
    train(config_from_dict(restart_dict(250, fall_restart_start=250)), tmp_path / "late")
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("plain", "late"))
    assert_states_equal(
        {k: v for k, v in a.items() if k not in ("path", "config")},
        {k: v for k, v in b.items() if k not in ("path", "config")},
    )

    straight = train(config_from_dict(restart_dict(400)), tmp_path / "straight")
    rows = read_metrics(tmp_path / "straight" / "metrics.csv")
    long_restart = next(
        r for r in rows if r["kind"] == "restart" and int(r["length"]) - int(r["restart_from"]) > 3
    )
    split = int(long_restart["step"]) - 2  # the restart is in progress there
    train(config_from_dict(restart_dict(split)), tmp_path / "split")
    assert load_checkpoint(tmp_path / "split" / "state.pt")["episode"]["restart_at"] is not None
    assert_resumed_split_equals_straight(tmp_path, straight, rows)


def test_a_branch_may_switch_restarts_on_at_its_step_but_not_before(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "run")
    later = config_from_dict(restart_dict(400, fall_restart=1.0, fall_restart_start=250))
    assert branch(tmp_path / "run", tmp_path / "late", later).steps == 400
    kinds = {r["kind"] for r in read_metrics(tmp_path / "late" / "metrics.csv")}
    assert "restart" in kinds
    with pytest.raises(UserError, match=r"train\.fall_restart_start"):
        branch(tmp_path / "run", tmp_path / "early", config_from_dict(restart_dict(400)))
    assert not (tmp_path / "early").exists()


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"fall_restart": -0.1}, "train.fall_restart"),
        ({"fall_restart": 1.5}, "train.fall_restart"),
        ({"fall_restart_back_min": 0}, "train.fall_restart_back_min"),
        ({"fall_restart_back": 5, "fall_restart_back_min": 6}, "train.fall_restart_back"),
        ({"fall_restart_horizon": 0}, "train.fall_restart_horizon"),
        ({"fall_restart_memory": 0}, "train.fall_restart_memory"),
        ({"fall_restart_start": -1}, "train.fall_restart_start"),
    ],
)
def test_config_errors_name_the_key(keys, key):
    with pytest.raises(UserError, match=rf"r\.yaml: key '{key}' expects"):
        config_from_dict(restart_dict(400, **keys), "r.yaml")


def test_the_display_shows_the_falls_remembered(tmp_path):

    trainer = Trainer(config_from_dict(restart_dict(400)), tmp_path / "run")
    assert trainer.snapshot(0.0)["falls_remembered"] is None  # before its start step
    trainer.step = 60
    trainer.fall_memory.remember(1, np.zeros((5, 4), np.float32), 4)
    assert "falls remembered  1 " in stats_text(trainer.snapshot(0.0))


@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda d: d["episode"].__setitem__("restart_at", 10**6), "episode.restart_at"),
        (lambda d: d.__setitem__("fall_memory", {"seed": 1}), "'fall_memory' should be a list"),
        (lambda d: d["fall_memory"][0].__setitem__("seed", -1), "fall_memory.0.seed"),
        (lambda d: d["fall_memory"][0].pop("actions"), "'fall_memory.0.actions' is missing"),
        (
            lambda d: d["fall_memory"][0].__setitem__("actions", torch.zeros(5, 3)),
            "fall_memory.0.actions",
        ),
    ],
    ids=["restart-at", "memory-not-list", "bad-seed", "no-actions", "bad-shape"],
)
def test_a_damaged_restart_in_a_checkpoint_is_a_one_line_error(tmp_path, edit, needle):
    train(config_from_dict(restart_dict(225)), tmp_path / "run")  # inside a restart
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    assert state["fall_memory"] and state["episode"]["restart_at"] is not None
    edit(state)
    torch.save({k: v for k, v in state.items() if k != "path"}, tmp_path / "run" / "state.pt")
    with pytest.raises(UserError, match=re.escape(needle)):
        load_checkpoint(tmp_path / "run" / "state.pt")


def test_a_restart_file_keeps_the_falls_and_no_episode(tmp_path):
    train(config_from_dict(restart_dict(225)), tmp_path / "run")  # inside a restart
    restart = load_checkpoint(tmp_path / "run" / "restart.pt")
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    assert restart["episode"]["restart_at"] is None
    assert [f["seed"] for f in restart["fall_memory"]] == [f["seed"] for f in state["fall_memory"]]
    assert state["episode"]["restart_at"] is not None
    assert branch(tmp_path / "run" / "restart.pt", tmp_path / "moved").steps == 225


def test_a_curriculum_switch_forgets_the_previous_envs_falls(tmp_path):
    from bipedal_cli.curriculum import switch_env

    trainer = Trainer(config_from_dict(restart_dict(400)), tmp_path / "run")
    trainer.fall_memory.remember(1, np.zeros((5, 4), np.float32), 4)
    switch_env(trainer, "BipedalWalkerHardcore-v3", clear_buffer=False)
    assert len(trainer.fall_memory) == 0  # Walker's falls are not on Hardcore's terrain
