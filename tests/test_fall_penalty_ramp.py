"""The fall-penalty ramp (train.fall_penalty_final): each episode's learner sees the penalty of the
step it starts at; resume stays exact; a branch may start the ramp at its step."""

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.metrics import read_metrics
from bipedal_cli.resume import branch, resume
from bipedal_cli.schedule import fall_penalty_at
from bipedal_cli.train import train

from .conftest import stats_text, tiny_dict
from .test_hardcore_features import SHAPING, featured
from .test_train import assert_states_equal

RAMP = {"fall_penalty_final": -40.0, "fall_penalty_ramp_start": 50, "fall_penalty_ramp_end": 200}


def ramped(**train_keys) -> dict:
    return featured(**{**RAMP, **train_keys})


def test_the_penalty_is_constant_then_linear_then_final():
    cfg = config_from_dict(ramped()).train
    assert [fall_penalty_at(s, cfg) for s in (0, 50, 125, 162, 200, 10**9)] == [
        -7.0,
        -7.0,
        pytest.approx(-23.5, rel=1e-12),
        pytest.approx(-31.64, rel=1e-12),
        -40.0,
        -40.0,
    ]
    constant = config_from_dict(featured()).train
    assert fall_penalty_at(10**9, constant) == -7.0
    assert fall_penalty_at(0, config_from_dict(tiny_dict()).train) is None  # the env's -100
    step = config_from_dict(featured(**{**RAMP, "fall_penalty_ramp_end": 50})).train
    assert (fall_penalty_at(50, step), fall_penalty_at(51, step)) == (-7.0, -40.0)


def test_each_episode_sees_the_penalty_of_the_step_it_starts_at(tmp_path):
    """On a fall the env's reward is -100; the learner's is the penalty, times the scale:
    shaped / scale - (env return + 100) is the penalty the episode saw."""
    train(config_from_dict(ramped(total_steps=600)), tmp_path / "run")
    rows = [r for r in read_metrics(tmp_path / "run" / "metrics.csv") if r["kind"] == "episode"]
    start, seen = 0, []
    for row in rows:
        if row["fell"] == "1":
            shaped, env_return = float(row["shaped_return"]), float(row["return"])
            seen.append((start, shaped / SHAPING["reward_scale"] - env_return - 100.0))
        start = int(row["step"])
    cfg = config_from_dict(ramped()).train
    for step, penalty in seen:
        assert penalty == pytest.approx(fall_penalty_at(step, cfg), abs=2e-3), step
    starts = [s for s, _ in seen]
    assert min(starts) <= 50 and max(starts) >= 200  # before, within and after the ramp
    assert any(50 < s < 200 for s in starts)


def test_resume_is_exact_across_the_ramp(tmp_path):
    slow = {"fall_penalty_ramp_start": 100, "fall_penalty_ramp_end": 300}
    straight = train(config_from_dict(ramped(total_steps=400, **slow)), tmp_path / "straight")
    train(config_from_dict(ramped(total_steps=230, **slow)), tmp_path / "split")
    cut = load_checkpoint(tmp_path / "split" / "state.pt")["episode"]
    assert len(cut["actions"]) > 0 and -40.0 < cut["fall_penalty"] < -7.0  # mid-ramp, cut
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes >= 2
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in a.items() if k != "path"}, {k: v for k, v in b.items() if k != "path"}
    )


def test_a_checkpoint_without_the_episodes_penalty_resumes_with_the_configs(tmp_path):
    """state.pt files written before the ramp existed: the episode saw the config's penalty."""
    train(config_from_dict(featured(total_steps=230)), tmp_path / "old")
    train(config_from_dict(featured(total_steps=230)), tmp_path / "new")
    state = load_checkpoint(tmp_path / "old" / "state.pt")
    del state["episode"]["fall_penalty"]
    torch.save({k: v for k, v in state.items() if k != "path"}, tmp_path / "old" / "state.pt")
    resume(tmp_path / "old", total_steps=300)
    resume(tmp_path / "new", total_steps=300)
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("old", "new"))
    assert torch.equal(a["buffer"]["reward"], b["buffer"]["reward"])


def test_a_bad_penalty_in_a_checkpoint_is_a_one_line_error(tmp_path):
    train(config_from_dict(ramped(total_steps=230)), tmp_path / "run")
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    state["episode"]["fall_penalty"] = "steep"
    torch.save({k: v for k, v in state.items() if k != "path"}, tmp_path / "run" / "state.pt")
    with pytest.raises(UserError, match=r"'episode\.fall_penalty' should be null or a finite"):
        load_checkpoint(tmp_path / "run" / "state.pt")


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"fall_penalty": None, "fall_penalty_final": -20.0}, "train.fall_penalty_final"),
        ({**RAMP, "fall_penalty_ramp_end": 49}, "train.fall_penalty_ramp_end"),
        ({**RAMP, "fall_penalty_ramp_start": -1}, "train.fall_penalty_ramp_start"),
    ],
)
def test_config_errors_name_the_key(keys, key):
    data = featured()
    data["train"].update(keys)
    with pytest.raises(UserError, match=key.replace(".", r"\.")):
        config_from_dict(data, "ramp.yaml")


def test_a_branch_may_start_the_ramp_at_its_step_but_not_before(tmp_path):
    train(config_from_dict(featured(total_steps=200)), tmp_path / "run")
    late = featured(total_steps=260, **{**RAMP, "fall_penalty_ramp_start": 200})
    assert branch(tmp_path / "run", tmp_path / "late", config_from_dict(late)).steps == 260
    with pytest.raises(UserError, match=r"train\.fall_penalty_ramp_start"):
        branch(tmp_path / "run", tmp_path / "early", config_from_dict(ramped()))
    assert not (tmp_path / "early").exists()


def test_the_display_shows_the_penalty_of_the_episode_in_progress(tmp_path):
    from bipedal_cli.train import Trainer

    trainer = Trainer(config_from_dict(ramped()), tmp_path / "run")
    trainer.step = 125
    trainer.start_episode()
    assert "fall penalty  -23.5" in stats_text(trainer.snapshot(0.0))
    plain = Trainer(config_from_dict(featured()), tmp_path / "plain")
    assert plain.snapshot(0.0)["fall_penalty"] is None  # no ramp: the line stays as it was
