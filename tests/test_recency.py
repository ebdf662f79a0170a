"""Emphasizing Recent Experience (train.replay_recency): the window c_k against the paper's
formula written out slowly, the buffer's draw from its newest transitions (across the ring's
wrap), the sampling distribution of a whole sequence, the trainer's use of it, and an exact
resume."""

import math
from fractions import Fraction

import numpy as np
import pytest

from bipedal_cli.buffer import ReplayBuffer
from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.recency import SEQUENCE, recency_at, recent_window
from bipedal_cli.resume import branch, resume
from bipedal_cli.train import Trainer, train

from .conftest import stats_text, tiny_dict
from .test_train import assert_states_equal

ERE = {"replay_recency": 0.99, "replay_recency_end": 600, "replay_recent_min": 20}


def ere_config(total_steps: int, **keys):
    return config_from_dict(tiny_dict(total_steps=total_steps, **{**ERE, **keys}))


def reference_window(n: int, eta: float, k_paper: int, big_k: int, c_min: int) -> int:
    """Wang and Ross's eq.: c_k = max{N eta^(k 1000 / K), c_min}, k = 1..K, capped at N."""
    c = max(n * eta ** (k_paper * 1000 / big_k), c_min)
    return min(n, int(math.floor(c)))


def test_eta_is_off_constant_or_annealed_to_one():
    off = config_from_dict(tiny_dict()).train
    assert recency_at(123, off) is None
    constant = ere_config(400, replay_recency_end=None).train
    assert [recency_at(s, constant) for s in (0, 10**9)] == [0.99, 0.99]
    t = ere_config(400).train
    got = [recency_at(s, t) for s in (0, 300, 600, 10**9)]
    assert got == pytest.approx([0.99, 0.995, 1.0, 1.0], abs=1e-15)


@pytest.mark.parametrize("n, eta, c_min", [(1_000_000, 0.996, 5000), (7_000, 0.996, 5000)])
def test_the_window_is_the_papers_with_k_cycling_over_1000_updates(n, eta, c_min):
    for update_index in (0, 1, 499, 998, 999, 1000, 123_456):
        k = 1 + update_index % 1000
        expected = reference_window(n, eta, k, SEQUENCE, c_min)
        assert recent_window(n, eta, update_index, c_min) == expected
    assert recent_window(n, 1.0, 777, c_min) == n  # eta 1: the whole buffer
    assert recent_window(100, 0.5, 5, c_min) == 100  # c_min above N: capped at N
    with pytest.raises(ValueError):
        recent_window(0, eta, 0, c_min)


def filled(capacity: int, count: int) -> ReplayBuffer:
    buffer = ReplayBuffer(capacity, obs_dim=1, act_dim=1)
    for i in range(count):  # reward i marks the i-th transition stored
        buffer.add([i], [0.0], float(i), [i], False)
    return buffer


@pytest.mark.parametrize("capacity, count", [(50, 30), (50, 50), (50, 137)])
def test_the_buffer_draws_only_its_newest_transitions(capacity, count):
    buffer, rng = filled(capacity, count), np.random.default_rng(0)
    newest = count - 1
    for window in (1, 7, len(buffer)):
        drawn = buffer.sample_recent(4000, window, rng)["reward"]
        assert set(drawn.astype(int)) == set(range(newest - window + 1, newest + 1))
    for bad in (0, len(buffer) + 1):
        with pytest.raises(ValueError):
            buffer.sample_recent(4, bad, rng)


def test_a_whole_sequence_draws_ages_with_the_papers_mixture():
    """Over 1000 updates, P(age a) = (1/K) sum_k [a < c_k] / c_k: each update uniform over its
    window. Exact, with one draw of every age in every window."""
    n, eta, c_min = 400, 0.995, 30
    windows = [recent_window(n, eta, i, c_min) for i in range(SEQUENCE)]
    exact = [sum(Fraction(1, c) for c in windows if a < c) / SEQUENCE for a in range(n)]
    assert sum(exact) == 1
    buffer, rng = filled(n, n), np.random.default_rng(1)
    counts = np.zeros(n)
    for c in windows:
        ages = (n - 1) - buffer.sample_recent(400, c, rng)["reward"].astype(int)
        np.add.at(counts, ages, 1)
    share = counts / counts.sum()
    newest, oldest = float(sum(exact[:10])), float(sum(exact[-100:]))
    assert share[:10].sum() == pytest.approx(newest, rel=0.05)
    assert share[-100:].sum() == pytest.approx(oldest, rel=0.05)
    assert newest > 5 * oldest / 10  # the newest ten far above the oldest hundred's mean ten


def test_each_update_draws_the_window_of_its_step_and_update_count(tmp_path, monkeypatch):
    trainer = Trainer(ere_config(300, replay_recency=0.97), tmp_path / "run")
    drawn: list[tuple[int, int]] = []
    sample_recent = trainer.buffer.sample_recent

    def recording(batch_size, window, rng):
        t, n = trainer.step, len(trainer.buffer)
        expected = recent_window(n, recency_at(t, trainer.cfg.train), trainer.agent.updates, 20)
        drawn.append((window, expected))
        return sample_recent(batch_size, window, rng)

    monkeypatch.setattr(trainer.buffer, "sample_recent", recording)
    monkeypatch.setattr(trainer.buffer, "sample", lambda *a: pytest.fail("a uniform draw"))
    trainer.run()
    assert len(drawn) == 300 - trainer.cfg.train.warmup_steps
    assert all(w == e for w, e in drawn)
    assert len({w for w, _ in drawn}) > 20 and min(w for w, _ in drawn) == 20


def test_a_run_with_ere_resumes_exactly_and_differs_from_uniform_replay(tmp_path):
    straight = train(ere_config(400), tmp_path / "straight")
    train(ere_config(230), tmp_path / "split")
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes
    s, r = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in s.items() if k != "path"}, {k: v for k, v in r.items() if k != "path"}
    )
    train(config_from_dict(tiny_dict(total_steps=400)), tmp_path / "uniform")
    u = load_checkpoint(tmp_path / "uniform" / "state.pt")
    assert any(not (v == u["agent"]["actor"][k]).all() for k, v in s["agent"]["actor"].items())


def test_a_branch_may_not_switch_it_on(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "run")
    with pytest.raises(UserError, match=r"train\.replay_recency"):
        branch(tmp_path / "run", tmp_path / "ere", ere_config(300))
    assert not (tmp_path / "ere").exists()


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"replay_recency": 1.0}, "train.replay_recency"),
        ({"replay_recency": 0.0}, "train.replay_recency"),
        ({"replay_recency_end": 0}, "train.replay_recency_end"),
        ({"replay_recent_min": 0}, "train.replay_recent_min"),
    ],
)
def test_config_errors_name_the_key(keys, key):
    with pytest.raises(UserError, match=rf"ere\.yaml: key '{key}' expects"):
        config_from_dict(tiny_dict(**{**ERE, **keys}), "ere.yaml")


def test_the_display_shows_eta(tmp_path):

    trainer = Trainer(ere_config(400), tmp_path / "run")
    trainer.step = 300
    assert trainer.snapshot(0.0)["replay_recency"] == pytest.approx(0.995)
    assert "recent replay  eta 0.99500" in stats_text(trainer.snapshot(0.0))
    assert (
        Trainer(config_from_dict(tiny_dict()), tmp_path / "p").snapshot(0.0)["replay_recency"]
        is None
    )
