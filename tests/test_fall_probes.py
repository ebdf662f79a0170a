"""Probes (train.fall_restart_probe): fresh episodes played by the deterministic policy, whose
falls are the only ones restarts rebuild; the draw, the run's bookkeeping, an exact resume inside
a probe, and the key and checkpoint errors."""

import re

import numpy as np
import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.fall_restarts import draws_probe, remembers_fall
from bipedal_cli.metrics import read_metrics
from bipedal_cli.train import Trainer, train

from .test_fall_restarts import assert_resumed_split_equals_straight, restart_dict


def probe_dict(total_steps: int, **train_keys) -> dict:
    """Restarts from step 20, half the fresh episodes probes; with each action held for 4 env
    steps the tiny agent falls within a few dozen policy steps, deterministic or not."""
    keys = {"fall_restart_probe": 0.5, "warmup_steps": 20, "fall_restart_start": 20}
    data = restart_dict(total_steps, **{**keys, **train_keys})
    data["agent"]["action_repeat"] = 4
    return data


def test_the_probe_draw_and_which_falls_are_remembered():
    t = config_from_dict(probe_dict(400, fall_restart_start=50)).train
    rng = np.random.default_rng(0)
    before = rng.bit_generator.state
    assert not draws_probe(rng, t, 50) and rng.bit_generator.state == before  # nothing drawn
    probes = sum(draws_probe(rng, t, 51) for _ in range(2000))
    assert 850 < probes < 1150  # 1000 expected
    t.fall_restart_probe = 0.0
    state = rng.bit_generator.state
    assert not draws_probe(rng, t, 51) and rng.bit_generator.state == state  # off: no draw
    t.fall_restart_probe = 1.0
    assert all(draws_probe(rng, t, 51) for _ in range(50))

    # (step, fresh, probe, fell) -> remembered, with probes on and off
    assert remembers_fall(t, 51, True, True, True)
    assert not remembers_fall(t, 51, True, False, True)  # a stochastic fall: not with probes on
    assert not remembers_fall(t, 51, False, False, True)  # a restart's fall: never
    assert not remembers_fall(t, 51, True, True, False)
    assert not remembers_fall(t, 50, True, True, True)  # before the start step
    t.fall_restart_probe = 0.0
    assert remembers_fall(t, 51, True, False, True)  # session 22's rule: any fresh fall


def test_probes_act_deterministically_and_only_their_falls_are_remembered(tmp_path):
    trainer = Trainer(config_from_dict(probe_dict(400)), tmp_path / "run")
    calls = []
    act = trainer.agent.act

    def spy(obs, deterministic=False, actor=None):
        calls.append((deterministic, trainer.runner.episode.probe))
        return act(obs, deterministic, actor=actor)

    trainer.agent.act = spy
    trainer.run()
    assert calls and all(deterministic == probe for deterministic, probe in calls)
    assert any(probe for _, probe in calls) and not all(probe for _, probe in calls)
    rows = read_metrics(tmp_path / "run" / "metrics.csv")
    probes = [r for r in rows if r["kind"] == "probe"]
    assert probes and all(int(r["step"]) > 20 for r in probes)
    assert {r["kind"] for r in rows} >= {"episode", "probe", "restart"}
    fallen = [r for r in probes if r["fell"] == "1"]
    assert fallen and len(trainer.fall_memory) == len(fallen)  # probes' falls only
    fresh = [r for r in rows if r["kind"] in ("episode", "probe")]
    assert list(trainer.recent_returns) == pytest.approx(
        [float(r["return"]) for r in fresh][-len(trainer.recent_returns) :], abs=1e-3
    )


def test_a_run_resumes_exactly_inside_a_probe(tmp_path):
    straight = train(config_from_dict(probe_dict(400)), tmp_path / "straight")
    rows = read_metrics(tmp_path / "straight" / "metrics.csv")
    ends = [int(r["step"]) for r in rows if r["kind"] in ("episode", "probe", "restart")]
    long_probe = next(
        r
        for r, previous in zip(rows[1:], rows, strict=False)
        if r["kind"] == "probe" and int(r["step"]) - int(previous["step"]) > 3
    )
    split = int(long_probe["step"]) - 2  # the probe is in progress there
    assert split not in ends
    train(config_from_dict(probe_dict(split)), tmp_path / "split")
    assert load_checkpoint(tmp_path / "split" / "state.pt")["episode"]["probe"] is True
    assert_resumed_split_equals_straight(tmp_path, straight, rows)


@pytest.mark.parametrize("value", [-0.1, 1.5])
def test_a_probe_share_outside_0_1_is_a_key_error(value):
    with pytest.raises(UserError, match=r"r\.yaml: key 'train\.fall_restart_probe' expects"):
        config_from_dict(probe_dict(400, fall_restart_probe=value), "r.yaml")


def test_a_damaged_probe_flag_in_a_checkpoint_is_a_one_line_error(tmp_path):
    train(config_from_dict(probe_dict(120)), tmp_path / "run")
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    state["episode"]["probe"] = 1
    torch.save({k: v for k, v in state.items() if k != "path"}, tmp_path / "run" / "state.pt")
    with pytest.raises(UserError, match=re.escape("episode.probe")):
        load_checkpoint(tmp_path / "run" / "state.pt")
