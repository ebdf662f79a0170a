"""``train.refill_policies``: a restart's refill played by earlier policies in turn, one per
episode, instead of by the restart's own actor alone (:mod:`bipedal_cli.refill`)."""

import shutil
from types import SimpleNamespace

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.refill import refill_actor, refill_policy_index
from bipedal_cli.resume import branch, resume
from bipedal_cli.snapshot import refill_phase
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_train import assert_states_equal


@pytest.fixture
def stopped_run(tmp_path):
    """A tiny run stopped at 230 with policies kept at 100 and 200, and its restart file."""
    cfg = tiny_dict(total_steps=230, eval_every=100, keep_policies=True)
    train(config_from_dict(cfg), tmp_path / "run")
    shutil.copyfile(tmp_path / "run" / "restart.pt", tmp_path / "restart.pt")
    return tmp_path / "run"


def restarted(tmp_path, name, policies, total=400, refill=100):
    explicit = {
        "train.refill_steps": refill,
        "train.total_steps": total,
        "train.refill_policies": [str(p) for p in policies],
    }
    branch(tmp_path / "restart.pt", tmp_path / name, explicit=explicit)
    state = load_checkpoint(tmp_path / name / "state.pt")
    return {k: v for k, v in state.items() if k != "path"}


def kept(run, step):
    return run / "policies" / f"step-{step}.pt"


def test_policy_by_episode_in_turn_while_the_refill_lasts():
    assert [refill_policy_index(240, 330, e, 3) for e in range(5)] == [0, 1, 2, 0, 1]
    assert refill_policy_index(329, 330, 4, 3) == 1
    assert refill_policy_index(330, 330, 4, 3) is None  # the refill is over: the agent's actor
    assert refill_policy_index(240, 330, 4, 0) is None  # no refill policies: the agent's actor


def test_the_restarts_own_policy_as_the_refill_policy_is_the_plain_refill(tmp_path, stopped_run):
    """Same weights, same noise generator: the same bits as a refill by the agent's actor."""
    own = tmp_path / "own-policy.pt"
    shutil.copyfile(stopped_run / "policy.pt", own)  # the actor at 230, the restart's
    plain = restarted(tmp_path, "plain", [])
    by_file = restarted(tmp_path, "by-file", [own])
    assert by_file["config"]["train"].pop("refill_policies") == [str(own)]
    plain["config"]["train"].pop("refill_policies")
    assert_states_equal(plain, by_file)


def test_earlier_policies_fill_the_buffer_with_their_own_actions(tmp_path, stopped_run):
    plain = restarted(tmp_path, "plain", [], total=330)  # stops where the refill ends
    first, second = kept(stopped_run, 100), kept(stopped_run, 200)
    mixed = restarted(tmp_path, "mixed", [first, second], total=330)
    swapped = restarted(tmp_path, "swap", [second, first], total=330)
    assert mixed["agent"]["updates"] == plain["agent"]["updates"]  # no update in either refill
    assert plain["buffer"]["size"] == mixed["buffer"]["size"] == 100
    actions = [torch.as_tensor(s["buffer"]["action"]) for s in (plain, mixed, swapped)]
    assert not torch.equal(actions[0], actions[1]) and not torch.equal(actions[1], actions[2])
    for net in ("actor", "critic"):  # nothing learned yet: the networks are the restart's
        for key, value in plain["agent"][net].items():
            assert torch.equal(value, mixed["agent"][net][key])


def test_the_trainer_acts_with_the_policy_of_its_episode_until_the_refill_ends(tmp_path):
    cfg = config_from_dict(tiny_dict(refill_policies=["a.pt", "b.pt"]))
    trainer = SimpleNamespace(cfg=cfg, step=240, refill_until=330, episodes=7)
    trainer.refill_actors = ["actor a", "actor b"]  # loaded already
    assert refill_actor(trainer) == "actor b"
    trainer.episodes = 8
    assert refill_actor(trainer) == "actor a"
    trainer.step = 330
    assert refill_actor(trainer) is None


def test_a_refill_with_policies_resumes_exactly_inside_it(tmp_path, stopped_run):
    policies = [kept(stopped_run, 100), kept(stopped_run, 200)]
    straight = restarted(tmp_path, "straight", policies, total=400)
    restarted(tmp_path, "split", policies, total=280)  # stops inside the refill (to 330)
    resume(tmp_path / "split", total_steps=400)
    split = load_checkpoint(tmp_path / "split" / "state.pt")
    skip = ("/counters/wall_time", "/config/train/total_steps")
    assert_states_equal(straight, {k: v for k, v in split.items() if k != "path"}, skip)


def test_a_bad_refill_policy_is_one_line_before_the_directory_is_made(tmp_path, stopped_run):
    with pytest.raises(UserError, match=r"train.refill_policies\[1\] .*nowhere.pt"):
        restarted(tmp_path, "x", [kept(stopped_run, 100), tmp_path / "nowhere.pt"])
    assert not (tmp_path / "x").exists()
    wide, walker = tiny_dict(total_steps=120), tmp_path / "wide"
    wide["agent"]["actor_hidden"] = 24
    train(config_from_dict(wide), walker)
    with pytest.raises(UserError, match=r"train.refill_policies\[0\] .*agent.actor_hidden"):
        restarted(tmp_path, "y", [walker / "policy.pt"])
    assert not (tmp_path / "y").exists()


def test_refill_policies_is_a_list_of_paths():
    assert config_from_dict(tiny_dict(refill_policies=["a.pt", "b.pt"])).train.refill_policies == [
        "a.pt",
        "b.pt",
    ]
    with pytest.raises(UserError, match=r"'train.refill_policies' expects list\[str\]"):
        config_from_dict(tiny_dict(refill_policies="a.pt"))
    with pytest.raises(UserError, match=r"'train.refill_policies\[1\]' expects str"):
        config_from_dict(tiny_dict(refill_policies=["a.pt", 3]))
    with pytest.raises(UserError, match="'train.refill_policies' expects a list of policy"):
        config_from_dict(tiny_dict(refill_policies=[""]))


def test_the_display_says_how_many_policies_refill():
    assert refill_phase(config_from_dict(tiny_dict()).train) == "refilling replay"
    two = config_from_dict(tiny_dict(refill_policies=["a.pt", "b.pt"])).train
    assert refill_phase(two) == "refilling replay (2 policies in turn)"


def test_cli_names_the_refill_policies_with_a_repeated_option(
    tmp_path, stopped_run, capsys, monkeypatch
):
    from .test_cli import run_cli

    first, second = kept(stopped_run, 100), kept(stopped_run, 200)
    into = tmp_path / "cli"
    args = ["resume", tmp_path / "restart.pt", "--into", into, "--steps", 280]
    monkeypatch.chdir(stopped_run)  # a relative path is stored resolved
    relative = first.relative_to(stopped_run)
    code, out, err = run_cli(
        [*args, "--refill-policy", relative, "--refill-policy", second], capsys
    )
    assert code == 0, err
    state = load_checkpoint(into / "state.pt")
    assert state["config"]["train"]["refill_policies"] == [str(first), str(second)]
    code, out, err = run_cli(["resume", stopped_run, "--refill-policy", first], capsys)
    assert code == 2 and "only with --into" in err and len(err.strip().splitlines()) == 1
    code, out, err = run_cli([*args[:3], tmp_path / "bad", "--refill-policy", tmp_path], capsys)
    assert code == 2 and "train.refill_policies[0]" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "bad").exists()


def test_a_restart_file_naming_lost_policies_says_how_to_refill_without_them(tmp_path, stopped_run):
    """A restarted run's own restart.pt keeps its refill policies in its config; after a move
    they may be gone, and the refusal says how to name others or none."""
    moved = tmp_path / "moved.pt"
    lost = tmp_path / "lost-policy.pt"
    shutil.copyfile(kept(stopped_run, 100), lost)
    restarted(tmp_path, "first", [lost], total=240, refill=5)
    shutil.copyfile(tmp_path / "first" / "restart.pt", moved)
    lost.unlink()
    with pytest.raises(UserError, match=r"lost-policy.pt: no such file; .*refill_policies=\[\]"):
        branch(moved, tmp_path / "second", explicit={"train.total_steps": 260})
    assert not (tmp_path / "second").exists()
    branch(moved, tmp_path / "second", overrides=["train.refill_policies=[]"])
    state = load_checkpoint(tmp_path / "second" / "state.pt")
    assert state["config"]["train"]["refill_policies"] == []
