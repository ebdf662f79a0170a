"""The larger batch from a step on (agent.batch_size_final): B(t) switches after its step; a run
draws B(t) transitions per update, is the plain run to the bit up to the switch, resumes exactly
across it, and may be branched into it at its step but not before."""

import pytest

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.resume import branch, resume
from bipedal_cli.schedule import batch_size_at
from bipedal_cli.train import Trainer, train

from .conftest import tiny_dict
from .test_train import assert_states_equal

LARGER = {"batch_size_final": 48, "batch_size_start": 250}


def larger_dict(total_steps: int, **agent_keys) -> dict:
    data = tiny_dict(total_steps=total_steps)
    data["agent"].update({**LARGER, **agent_keys})
    return data


def test_the_batch_grows_after_its_step():
    agent = config_from_dict(larger_dict(400)).agent
    small = agent.batch_size
    assert [batch_size_at(s, agent) for s in (0, 250, 251, 10**9)] == [small, small, 48, 48]
    assert batch_size_at(10**9, config_from_dict(tiny_dict()).agent) == small


@pytest.mark.parametrize(
    "keys, key",
    [
        ({"batch_size_final": 0}, "agent.batch_size_final"),
        ({"batch_size_final": 2**21}, "agent.batch_size_final"),
        ({"batch_size_start": -1}, "agent.batch_size_start"),
    ],
)
def test_config_errors_name_the_key(keys, key):
    with pytest.raises(UserError, match=rf"big\.yaml: key '{key}' expects"):
        config_from_dict(larger_dict(400, **keys), "big.yaml")


def test_each_update_draws_the_scheduled_batch(tmp_path, monkeypatch):
    trainer = Trainer(config_from_dict(larger_dict(300)), tmp_path / "run")
    drawn: list[tuple[int, int]] = []
    sample = trainer.buffer.sample

    def recording_sample(batch_size, rng):
        drawn.append((trainer.step, batch_size))
        return sample(batch_size, rng)

    monkeypatch.setattr(trainer.buffer, "sample", recording_sample)
    trainer.run()
    small = trainer.cfg.agent.batch_size
    assert drawn and all(b == (small if s <= 250 else 48) for s, b in drawn)
    assert {b for _, b in drawn} == {small, 48}


def test_the_run_is_the_plain_run_up_to_the_switch_and_resumes_exactly_across_it(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "plain")
    train(config_from_dict(larger_dict(250)), tmp_path / "early")
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("plain", "early"))
    for name in ("actor", "critic"):
        assert_states_equal(a["agent"][name], b["agent"][name])

    straight = train(config_from_dict(larger_dict(400)), tmp_path / "straight")
    train(config_from_dict(larger_dict(230)), tmp_path / "split")
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes
    s, r = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in s.items() if k != "path"}, {k: v for k, v in r.items() if k != "path"}
    )


def test_a_branch_may_switch_it_on_at_its_step_but_not_before(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "run")
    assert branch(tmp_path / "run", tmp_path / "late", config_from_dict(larger_dict(300))).steps
    late = load_checkpoint(tmp_path / "late" / "state.pt")
    resume(tmp_path / "run", total_steps=300)
    plain = load_checkpoint(tmp_path / "run" / "state.pt")
    actor_p, actor_l = plain["agent"]["actor"], late["agent"]["actor"]
    assert any(not (v == actor_l[k]).all() for k, v in actor_p.items())  # the batch changed it
    with pytest.raises(UserError, match=r"agent\.batch_size_start"):
        branch(
            tmp_path / "run",
            tmp_path / "early",
            config_from_dict(larger_dict(300, batch_size_start=200)),
        )
    assert not (tmp_path / "early").exists()


def test_the_display_shows_the_batch_it_draws(tmp_path):
    from rich.console import Console

    from bipedal_cli.display import TrainingDisplay

    trainer = Trainer(config_from_dict(larger_dict(400)), tmp_path / "run")
    assert trainer.snapshot(0.0)["batch_size"] == trainer.cfg.agent.batch_size
    trainer.step = 251
    display = TrainingDisplay(Console(width=200, record=True))
    display.snapshot = trainer.snapshot(0.0)
    display.console.print(display.stats_table())
    assert "batch  48 " in display.console.export_text()
    assert (
        Trainer(config_from_dict(tiny_dict()), tmp_path / "p").snapshot(0.0)["batch_size"] is None
    )
