"""A new run from a trained policy (train.init_policy, agent.actor_update_start): it starts with
that actor, acts with it during the warm-up, leaves it and the temperature alone while only the
critics learn, resumes exactly without the file, and refuses a file that does not fit."""

import hashlib
import shutil

import pytest
import torch
import yaml

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.networks import make_actor
from bipedal_cli.resume import resume
from bipedal_cli.schedule import actor_frozen
from bipedal_cli.train import Trainer, new_trainer, train

from .conftest import tiny_dict
from .test_cli import run_cli
from .test_train import assert_states_equal


@pytest.fixture(scope="module")
def parent(tmp_path_factory):
    """A tiny trained policy file to start from."""
    run = tmp_path_factory.mktemp("parent") / "run"
    train(config_from_dict(tiny_dict(total_steps=200)), run)
    return run / "policy.pt"


def warm_dict(parent, **agent_keys) -> dict:
    data = tiny_dict(total_steps=250, warmup_steps=100)
    data["seed"] = 5
    data["train"]["init_policy"] = str(parent)
    data["agent"].update({"init_alpha": 0.3, "actor_update_start": 300, **agent_keys})
    return data


def actors_equal(a: dict, b: dict) -> bool:
    return a.keys() == b.keys() and all(torch.equal(a[k], b[k]) for k in a)


def test_the_update_leaves_the_actor_up_to_its_step():
    agent = config_from_dict(tiny_dict()).agent
    assert not any(actor_frozen(s, agent) for s in (0, 1, 10**9))  # 0: never frozen
    agent.actor_update_start = 300
    assert [actor_frozen(s, agent) for s in (0, 300, 301)] == [True, True, False]


def test_a_run_starts_from_the_policy_and_only_its_critics_learn_until_the_step(tmp_path, parent):
    start = load_checkpoint(parent)["actor"]
    train(config_from_dict(warm_dict(parent)), tmp_path / "warm")
    state = load_checkpoint(tmp_path / "warm" / "state.pt")
    assert state["agent"]["updates"] == 150  # the critics learned ...
    assert actors_equal(state["agent"]["actor"], start)  # ... the actor did not
    assert float(state["agent"]["log_alpha"].exp()) == pytest.approx(0.3)  # nor the temperature
    # but Adam's moments did average the actor's gradients: steps of size zero
    adam = state["agent"]["actor_opt"]["state"][0]
    assert float(adam["step"]) == 150 and bool(adam["exp_avg_sq"].gt(0).any())
    fresh = Trainer(config_from_dict(warm_dict(parent)), tmp_path / "fresh").agent
    moved = fresh.critic.state_dict()
    assert any(not torch.equal(v, state["agent"]["critic"][k]) for k, v in moved.items())
    resume(tmp_path / "warm", total_steps=400)
    after = load_checkpoint(tmp_path / "warm" / "state.pt")["agent"]
    assert not actors_equal(after["actor"], start)  # from step 300 on the actor learns too


def test_the_warm_up_acts_with_the_policy_not_at_random(tmp_path, parent):
    cfg = config_from_dict(warm_dict(parent))
    trainer = new_trainer(cfg, tmp_path / "run")
    trainer.run(total_steps=60)  # all warm-up (100 steps): no update yet
    actor = make_actor(cfg.agent, trainer.obs_dim, trainer.act_dim)
    actor.load_state_dict(load_checkpoint(parent)["actor"])
    noise = torch.Generator().manual_seed(cfg.seed + 1)  # the agent's exploration noise
    b = trainer.buffer
    with torch.inference_mode():
        want = torch.stack(
            [actor.sample_action(torch.as_tensor(o)[None], generator=noise)[0] for o in b.obs[:60]]
        )
    assert torch.equal(torch.as_tensor(b.action[:60]), want)


def test_resume_needs_no_file_and_matches_the_uninterrupted_run(tmp_path, parent):
    own = tmp_path / "parent.pt"
    shutil.copy(parent, own)
    data = warm_dict(own, actor_update_start=200, actor_anchor=3.0)
    data["train"]["init_policy_sha256"] = hashlib.sha256(own.read_bytes()).hexdigest()
    straight_cfg = config_from_dict(data)
    straight_cfg.train.total_steps = 400
    train(straight_cfg, tmp_path / "straight")
    train(config_from_dict(data), tmp_path / "split")  # to 250
    own.unlink()  # read once, when the run starts
    resume(tmp_path / "split", total_steps=400)
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "split"))
    skip = ("/counters/wall_time", "/path", "/config/train/total_steps")
    assert_states_equal(a, b, skip=skip)
    assert actors_equal(b["agent"]["anchor"], load_checkpoint(parent)["actor"])  # never moves


def test_the_anchor_holds_the_actor_near_the_policy_it_started_from(tmp_path, parent):
    start = load_checkpoint(parent)
    cfg = config_from_dict(start["config"])
    mu0 = make_actor(cfg.agent, 24, 4)
    mu0.load_state_dict(start["actor"])

    def drift(**anchor):
        data = warm_dict(parent, actor_update_start=100, **anchor)
        data["train"]["total_steps"] = 400
        run = train(config_from_dict(data), tmp_path / f"run-{anchor}").run_dir
        state = load_checkpoint(run / "state.pt")
        mu = make_actor(cfg.agent, 24, 4)
        mu.load_state_dict(state["agent"]["actor"])
        obs = torch.as_tensor(state["buffer"]["obs"][:250])
        with torch.no_grad():
            (m, s), (m0, s0) = mu.distribution_params(obs), mu0.distribution_params(obs)
        return float((m - m0).pow(2).sum(1).mean()), float((s - s0).pow(2).sum(1).mean())

    free, held, held_kl = drift(), drift(actor_anchor=1000.0), drift(actor_anchor_kl=1000.0)
    assert held[0] < free[0] / 10, (held, free)  # the mean anchor holds the mean ...
    assert held_kl[0] < free[0] / 10 and held_kl[1] < free[1] / 10, (held_kl, free)  # KL: both


def test_the_anchor_needs_the_policy_it_anchors_to():
    data = tiny_dict()
    data["agent"]["actor_anchor"] = 10.0
    with pytest.raises(UserError, match="agent.actor_anchor"):
        config_from_dict(data)


def test_a_file_that_does_not_fit_is_one_line(tmp_path, parent, capsys):
    def train_cli(**edits):
        data = warm_dict(parent)
        for section, keys in edits.items():
            data[section].update(keys)
        path = tmp_path / "warm.yaml"
        path.write_text(yaml.safe_dump(data))
        return run_cli(["train", "--config", path, "--run-dir", tmp_path / "run"], capsys)

    cases = [
        ({"train": {"init_policy_sha256": "0" * 64}}, "sha256 is"),
        ({"train": {"init_policy": str(tmp_path / "none.pt")}}, "no such file"),
        ({"agent": {"history": 2}}, "agent.history is 1"),
        ({"agent": {"actor_hidden": 8}}, "agent.actor_hidden is 16"),
        ({"train": {"init_policy_sha256": "abc"}}, "64 lowercase hex"),
        ({"agent": {"actor_update_start": -1}}, "actor_update_start"),
    ]
    for edits, expected in cases:
        code, _, err = train_cli(**edits)
        assert code == 2 and expected in err and len(err.strip().splitlines()) == 1, (edits, err)
        assert not (tmp_path / "run" / "state.pt").exists()  # nothing written


def test_a_checksum_without_a_file_is_refused():
    data = tiny_dict()
    data["train"]["init_policy_sha256"] = "a" * 64
    with pytest.raises(UserError, match="null unless train.init_policy is set"):
        config_from_dict(data)


def test_a_warm_run_branches_into_an_anchor_up_to_its_actor_update_start(tmp_path, parent):
    """Before agent.actor_update_start the actor is the anchor itself: the anchor's term and its
    gradient are zero, so a branch there into another anchor is that config's run."""
    from bipedal_cli.resume import branch

    plain = warm_dict(parent, actor_update_start=200)
    plain["train"]["total_steps"] = 200
    train(config_from_dict(plain), tmp_path / "plain")
    anchored = warm_dict(parent, actor_update_start=200, actor_anchor=3.0)
    anchored["train"]["total_steps"] = 320
    branch(tmp_path / "plain", tmp_path / "branch", config_from_dict(anchored))
    train(config_from_dict(anchored), tmp_path / "straight")
    a, b = (load_checkpoint(tmp_path / n / "state.pt") for n in ("straight", "branch"))
    assert_states_equal(a, b, skip=("/counters/wall_time", "/path"))
    resume(tmp_path / "plain", total_steps=230)  # past the actor's start: no anchor now
    with pytest.raises(UserError, match="'agent.actor_update_start' expects a step at or after"):
        branch(tmp_path / "plain", tmp_path / "late", config_from_dict(anchored))
