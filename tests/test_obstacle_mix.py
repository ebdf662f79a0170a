"""More of some obstacles on the learner's Hardcore courses (train.obstacle_stump, _stairs, _pit,
_mix_start): the weighted draw and the draws it leaves alone, the courses it builds (read with
bipedal_cli.terrain), a run that is the plain run before its start and resumes exactly across
it, the branch rule, the key errors, the display and the checkpoint's flag."""

import re
from collections import Counter

import gymnasium as gym
import numpy as np
import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.envs import make_env, make_policy_env
from bipedal_cli.episodes import obstacle_mix_on
from bipedal_cli.errors import UserError
from bipedal_cli.obstacle_mix import (
    KIND_DRAW,
    ObstacleMix,
    WeightedKindGenerator,
    kind_probabilities,
)
from bipedal_cli.resume import branch, resume
from bipedal_cli.terrain import course_obstacles
from bipedal_cli.train import Trainer, train

from .conftest import stats_text, tiny_dict
from .test_train import assert_states_equal

MIX = {"obstacle_stump": 2.0, "obstacle_mix_start": 40}


def mix_dict(total_steps: int, **train_keys) -> dict:
    data = tiny_dict(total_steps=total_steps, **{**MIX, **train_keys})
    data["env"] = "BipedalWalkerHardcore-v3"
    data["agent"]["action_repeat"] = 3  # short episodes: several start in a tiny run
    return data


def kinds_on_courses(env: gym.Env, seeds) -> Counter:
    counts: Counter = Counter()
    for seed in seeds:
        env.reset(seed=seed)
        counts.update(span.kind for span in course_obstacles(env.unwrapped))
    return counts


def test_weights_become_probabilities_and_bad_ones_are_refused():
    assert kind_probabilities((2, 1, 1)).tolist() == [0.5, 0.25, 0.25]
    for bad in ((0, 0, 0), (1, -1, 1), (1, 1)):
        with pytest.raises(ValueError):
            kind_probabilities(bad)


def test_only_the_kind_draw_is_weighted_and_every_other_draw_passes_through():
    plain = np.random.default_rng(7)
    mixed = WeightedKindGenerator(np.random.default_rng(7), kind_probabilities((1, 0, 0)))
    assert mixed.integers(5, 10) == plain.integers(5, 10)
    assert mixed.uniform(-1, 1) == plain.uniform(-1, 1)
    assert mixed.integers(1, 3) == plain.integers(1, 3)  # a stump's size: not the kind
    assert {int(mixed.integers(*KIND_DRAW)) for _ in range(50)} == {1}  # stump only
    stairs = WeightedKindGenerator(np.random.default_rng(0), kind_probabilities((0, 1, 0)))
    assert {int(stairs.integers(*KIND_DRAW)) for _ in range(50)} == {2}


@pytest.mark.parametrize(
    "weights, only", [((1, 0, 0), "stump"), ((0, 1, 0), "stairs"), ((0, 0, 1), "pit")]
)
def test_a_course_holds_only_the_kinds_with_weight(weights, only):
    env = ObstacleMix(gym.make("BipedalWalkerHardcore-v3"), weights)
    counts = kinds_on_courses(env, range(3))
    assert set(counts) == {only} and counts[only] >= 10
    env.close()


def test_a_seed_fixes_the_course_and_the_mix_shifts_the_kinds():
    env = ObstacleMix(gym.make("BipedalWalkerHardcore-v3"), (2, 1, 1))
    first, again = (kinds_on_courses(env, range(12)) for _ in range(2))
    assert first == again
    stumps = first["stump"] / sum(first.values())
    plain = kinds_on_courses(gym.make("BipedalWalkerHardcore-v3"), range(12))
    assert stumps > 0.4 and plain["stump"] / sum(plain.values()) < 0.4
    env.reset()  # a first reset without a seed draws a course too


def test_the_policy_env_and_equal_weights_are_the_unmodified_env():
    cfg = config_from_dict(mix_dict(400))
    for env in (make_policy_env(cfg.env, cfg.agent), make_env(cfg.env, obstacle_weights=None)):
        assert not any(isinstance(e, ObstacleMix) for e in _wrappers(env))
    mixed = make_env(cfg.env, obstacle_weights=(2.0, 1.0, 1.0))
    assert any(isinstance(e, ObstacleMix) for e in _wrappers(mixed))
    equal = config_from_dict(mix_dict(400, obstacle_stump=3.0, obstacle_stairs=3.0, obstacle_pit=3))
    assert not obstacle_mix_on(equal.train, 10**6)
    assert [obstacle_mix_on(cfg.train, s) for s in (39, 40)] == [False, True]


def test_episodes_from_the_start_step_train_on_the_mix(tmp_path, monkeypatch):
    trainer = Trainer(config_from_dict(mix_dict(400)), tmp_path / "run")
    started: list[tuple[int, bool, bool]] = []
    start = trainer.runner.start

    def recording_start(*args):
        start(*args)
        wrapped = any(isinstance(e, ObstacleMix) for e in _wrappers(trainer.runner.env))
        started.append((trainer.step, trainer.runner.episode.obstacle_mix, wrapped))

    monkeypatch.setattr(trainer.runner, "start", recording_start)
    trainer.run()
    assert all(mixed == wrapped == (step >= 40) for step, mixed, wrapped in started)
    assert {mixed for _, mixed, _ in started} == {False, True}


def _wrappers(env):
    while isinstance(env, gym.Wrapper):
        yield env
        env = env.env


def test_the_run_is_the_plain_run_before_its_start_and_resumes_exactly_across_it(tmp_path):
    plain_dict = mix_dict(40, obstacle_stump=1.0)
    train(config_from_dict(plain_dict), tmp_path / "plain")
    train(config_from_dict(mix_dict(40)), tmp_path / "early")
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("plain", "early"))
    assert_states_equal(a["agent"], b["agent"])

    straight = train(config_from_dict(mix_dict(400)), tmp_path / "straight")
    train(config_from_dict(mix_dict(115)), tmp_path / "split")
    split = load_checkpoint(tmp_path / "split" / "state.pt")
    assert split["episode"]["obstacle_mix"] is True and len(split["episode"]["actions"]) > 0
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes
    s, r = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in s.items() if k != "path"}, {k: v for k, v in r.items() if k != "path"}
    )


def test_a_branch_may_switch_it_on_at_its_step_but_not_before(tmp_path):
    train(config_from_dict(mix_dict(50, obstacle_stump=1.0)), tmp_path / "run")
    assert branch(
        tmp_path / "run",
        tmp_path / "late",
        config_from_dict(mix_dict(260, **{"obstacle_mix_start": 50})),
    ).steps
    with pytest.raises(UserError, match=r"train\.obstacle_mix_start"):
        branch(tmp_path / "run", tmp_path / "early", config_from_dict(mix_dict(260)))
    assert not (tmp_path / "early").exists()


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"obstacle_stump": -1.0}, "train.obstacle_stump"),
        ({"obstacle_stairs": -0.5}, "train.obstacle_stairs"),
        ({"obstacle_stump": 0, "obstacle_stairs": 0, "obstacle_pit": 0}, "train.obstacle_pit"),
        ({"obstacle_mix_start": -1}, "train.obstacle_mix_start"),
        ({"fall_restart": 0.5}, "train.fall_restart"),
    ],
)
def test_config_errors_name_the_key(keys, key):
    with pytest.raises(UserError, match=rf"mix\.yaml: key '{re.escape(key)}' expects"):
        config_from_dict(mix_dict(400, **keys), "mix.yaml")


def test_the_display_shows_the_shares(tmp_path):

    trainer = Trainer(config_from_dict(mix_dict(400)), tmp_path / "run")
    assert trainer.snapshot(0.0)["obstacle_mix"] is None  # before its start
    trainer.step = 40
    assert "obstacles  stump 50% stairs 25% pit 25%" in stats_text(trainer.snapshot(0.0))


def test_a_damaged_mix_flag_in_a_checkpoint_is_a_one_line_error(tmp_path):
    train(config_from_dict(mix_dict(60)), tmp_path / "run")
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    state["episode"]["obstacle_mix"] = "yes"
    torch.save({k: v for k, v in state.items() if k != "path"}, tmp_path / "run" / "state.pt")
    with pytest.raises(UserError, match=re.escape("episode.obstacle_mix")):
        load_checkpoint(tmp_path / "run" / "state.pt")
