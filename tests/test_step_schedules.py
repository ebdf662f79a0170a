"""Schedules that switch at a policy step: the larger batch (agent.batch_size_final), more
updates per policy step (train.updates_per_step_final), more truncation
(agent.drop_per_critic_final), a falling target entropy (agent.target_entropy_final) and the
actor's smoothness term (agent.actor_smooth). Each switches after its step, is the plain run to
the bit up to the switch, resumes exactly across it, and may be branched into at its step but
not before."""

import pytest

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.resume import branch, resume
from bipedal_cli.schedule import (
    actor_smooth_at,
    batch_size_at,
    drop_per_critic_at,
    target_entropy_at,
    updates_at,
)
from bipedal_cli.train import Trainer, train

from .conftest import stats_text, tiny_dict
from .test_train import assert_states_equal

# name: (config section, its keys switched on at policy step 250)
SCHEDULES = {
    "batch": ("agent", {"batch_size_final": 48, "batch_size_start": 250}),
    "updates": ("train", {"updates_per_step_final": 2, "updates_per_step_start": 250}),
    "truncation": ("agent", {"drop_per_critic_final": 3, "drop_per_critic_start": 250}),
    "entropy": (
        "agent",
        {
            "target_entropy_final": -8.0,
            "target_entropy_decay_start": 250,
            "target_entropy_decay_end": 290,
        },
    ),
    "smooth": ("agent", {"actor_smooth": 1.0, "actor_smooth_start": 250}),
}
START_KEY = {
    "batch": "agent.batch_size_start",
    "updates": "train.updates_per_step_start",
    "truncation": "agent.drop_per_critic_start",
    "entropy": "agent.target_entropy_decay_start",
    "smooth": "agent.actor_smooth_start",
}


def switched_dict(name: str, total_steps: int, **keys) -> dict:
    section, switch = SCHEDULES[name]
    data = tiny_dict(total_steps=total_steps)
    data[section].update({**switch, **keys})
    return data


def test_the_batch_grows_after_its_step():
    agent = config_from_dict(switched_dict("batch", 400)).agent
    small = agent.batch_size
    assert [batch_size_at(s, agent) for s in (0, 250, 251, 10**9)] == [small, small, 48, 48]
    assert batch_size_at(10**9, config_from_dict(tiny_dict()).agent) == small


def test_the_updates_per_step_grow_after_their_step():
    t = config_from_dict(switched_dict("updates", 400)).train
    assert [updates_at(s, t) for s in (0, 250, 251, 10**9)] == [1, 1, 2, 2]
    assert updates_at(10**9, config_from_dict(tiny_dict()).train) == 1


def test_the_truncation_grows_after_its_step():
    agent = config_from_dict(switched_dict("truncation", 400)).agent
    assert [drop_per_critic_at(s, agent) for s in (0, 250, 251, 10**9)] == [1, 1, 3, 3]
    assert drop_per_critic_at(10**9, config_from_dict(tiny_dict()).agent) == 1


def test_the_target_entropy_falls_linearly_over_its_window():
    agent = config_from_dict(switched_dict("entropy", 400)).agent
    at = [target_entropy_at(s, agent, 4) for s in (0, 250, 260, 290, 10**9)]
    assert at == [-4.0, -4.0, pytest.approx(-5.0, rel=1e-12), -8.0, -8.0]
    agent.target_entropy = -2.0  # the ramp starts from H_T when it is set
    assert target_entropy_at(270, agent, 4) == pytest.approx(-5.0, rel=1e-12)
    assert target_entropy_at(10**9, config_from_dict(tiny_dict()).agent, 4) == -4.0


def test_the_smoothness_term_is_on_after_its_step():
    agent = config_from_dict(switched_dict("smooth", 400)).agent
    assert [actor_smooth_at(s, agent) for s in (0, 250, 251)] == [None, None, 1.0]
    assert actor_smooth_at(10**9, config_from_dict(tiny_dict()).agent) is None


def test_each_update_uses_the_scheduled_truncation_and_target_entropy(tmp_path, monkeypatch):
    import bipedal_cli.agent as agent_module

    data = switched_dict("truncation", 300)
    data["agent"].update(SCHEDULES["entropy"][1])
    trainer = Trainer(config_from_dict(data), tmp_path / "run")
    seen: dict[int, list] = {}
    target, temperature = agent_module.truncated_target, agent_module.temperature_loss

    def recording_target(*args):
        seen.setdefault(trainer.step, [None, None])[0] = args[6]  # drop_per_critic
        return target(*args)

    def recording_temperature(log_alpha, log_prob, target_entropy):
        seen.setdefault(trainer.step, [None, None])[1] = target_entropy
        return temperature(log_alpha, log_prob, target_entropy)

    monkeypatch.setattr(agent_module, "truncated_target", recording_target)
    monkeypatch.setattr(agent_module, "temperature_loss", recording_temperature)
    trainer.run()
    agent = trainer.cfg.agent
    assert seen and all(
        v == [drop_per_critic_at(s, agent), target_entropy_at(s, agent, 4)] for s, v in seen.items()
    )
    assert {v[0] for v in seen.values()} == {1, 3} and min(v[1] for v in seen.values()) == -8.0


@pytest.mark.parametrize(
    "name, keys, key",
    [
        ("batch", {"batch_size_final": 0}, "agent.batch_size_final"),
        ("batch", {"batch_size_final": 2**21}, "agent.batch_size_final"),
        ("batch", {"batch_size_start": -1}, "agent.batch_size_start"),
        ("updates", {"updates_per_step_final": -1}, "train.updates_per_step_final"),
        ("updates", {"updates_per_step_final": 65}, "train.updates_per_step_final"),
        ("updates", {"updates_per_step_start": -1}, "train.updates_per_step_start"),
        ("truncation", {"drop_per_critic_final": 5}, "agent.drop_per_critic_final"),
        ("truncation", {"drop_per_critic_start": -1}, "agent.drop_per_critic_start"),
        ("entropy", {"target_entropy_final": float("nan")}, "agent.target_entropy_final"),
        ("entropy", {"target_entropy_decay_end": 200}, "agent.target_entropy_decay_end"),
        ("entropy", {"target_entropy_decay_start": -1}, "agent.target_entropy_decay_start"),
        ("smooth", {"actor_smooth": 0.0}, "agent.actor_smooth"),
        ("smooth", {"actor_smooth_sigma": -0.1}, "agent.actor_smooth_sigma"),
        ("smooth", {"actor_smooth_start": -1}, "agent.actor_smooth_start"),
    ],
)
def test_config_errors_name_the_key(name, keys, key):
    with pytest.raises(UserError, match=rf"big\.yaml: key '{key}' expects"):
        config_from_dict(switched_dict(name, 400, **keys), "big.yaml")


def test_each_update_draws_the_scheduled_batch(tmp_path, monkeypatch):
    trainer = Trainer(config_from_dict(switched_dict("batch", 300)), tmp_path / "run")
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


def test_each_policy_step_makes_the_scheduled_updates(tmp_path, monkeypatch):
    trainer = Trainer(config_from_dict(switched_dict("updates", 300)), tmp_path / "run")
    updates_after: dict[int, int] = {}
    update = trainer.agent.update

    def counting_update(batch):
        updates_after[trainer.step] = updates_after.get(trainer.step, 0) + 1
        return update(batch)

    monkeypatch.setattr(trainer.agent, "update", counting_update)
    trainer.run()
    learning = [s for s in updates_after if s > trainer.cfg.train.warmup_steps]
    assert learning and all(updates_after[s] == (1 if s <= 250 else 2) for s in learning)
    assert set(updates_after.values()) == {1, 2} and max(updates_after) == 300


@pytest.mark.parametrize("name", SCHEDULES)
def test_the_run_is_the_plain_run_up_to_the_switch_and_resumes_exactly_across_it(tmp_path, name):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "plain")
    train(config_from_dict(switched_dict(name, 250)), tmp_path / "early")
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("plain", "early"))
    for part in ("actor", "critic"):
        assert_states_equal(a["agent"][part], b["agent"][part])

    straight = train(config_from_dict(switched_dict(name, 400)), tmp_path / "straight")
    train(config_from_dict(switched_dict(name, 230)), tmp_path / "split")
    second = resume(tmp_path / "split", total_steps=400)
    assert straight.episodes == second.episodes
    s, r = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    assert_states_equal(
        {k: v for k, v in s.items() if k != "path"}, {k: v for k, v in r.items() if k != "path"}
    )


@pytest.mark.parametrize("name", SCHEDULES)
def test_a_branch_may_switch_it_on_at_its_step_but_not_before(tmp_path, name):
    train(config_from_dict(tiny_dict(total_steps=250)), tmp_path / "run")
    switched = config_from_dict(switched_dict(name, 300))
    assert branch(tmp_path / "run", tmp_path / "late", switched).steps
    late = load_checkpoint(tmp_path / "late" / "state.pt")
    resume(tmp_path / "run", total_steps=300)
    plain = load_checkpoint(tmp_path / "run" / "state.pt")
    actor_p, actor_l = plain["agent"]["actor"], late["agent"]["actor"]
    assert any(not (v == actor_l[k]).all() for k, v in actor_p.items())  # the switch changed it
    too_early = {START_KEY[name].split(".")[1]: 200}
    with pytest.raises(UserError, match=START_KEY[name].replace(".", r"\.")):
        branch(
            tmp_path / "run",
            tmp_path / "early",
            config_from_dict(switched_dict(name, 300, **too_early)),
        )
    assert not (tmp_path / "early").exists()


@pytest.mark.parametrize(
    "name, key, shown",
    [("batch", "batch_size", "batch  48 "), ("updates", "updates_per_step", "updates/step  2 ")],
)
def test_the_display_shows_the_switched_value(tmp_path, name, key, shown):

    trainer = Trainer(config_from_dict(switched_dict(name, 400)), tmp_path / "run")
    before = trainer.cfg.agent.batch_size if name == "batch" else trainer.cfg.train.updates_per_step
    assert trainer.snapshot(0.0)[key] == before
    trainer.step = 251
    assert shown in stats_text(trainer.snapshot(0.0))
    assert Trainer(config_from_dict(tiny_dict()), tmp_path / "p").snapshot(0.0)[key] is None


@pytest.mark.parametrize(
    "name, key, before, shown",
    [
        ("truncation", "drop_per_critic", 1, "atoms dropped/critic  3 "),
        ("entropy", "target_entropy", -4.0, "target entropy  -5.00 "),
        ("smooth", "actor_smooth", None, "actor smoothness  1 "),
    ],
)
def test_the_display_shows_the_scheduled_agent_values(tmp_path, name, key, before, shown):
    trainer = Trainer(config_from_dict(switched_dict(name, 400)), tmp_path / "run")
    assert trainer.snapshot(0.0)[key] == before
    trainer.step = 260
    assert shown in stats_text(trainer.snapshot(0.0))
    assert Trainer(config_from_dict(tiny_dict()), tmp_path / "p").snapshot(0.0)[key] is None
