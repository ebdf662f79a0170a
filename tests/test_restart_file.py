"""``restart.pt``: a run's state without its replay buffer, and ``bipedal resume FILE --into DIR``
(the run goes on in a new directory after a refill of its buffer)."""

import re
import shutil

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.errors import UserError
from bipedal_cli.metrics import read_metrics, restart_metrics_text
from bipedal_cli.resume import branch, resume
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_train import assert_states_equal


def restarted(tmp_path, name="restarted", refill=60, total=400, source="run"):
    """The run at ``tmp_path/source`` continued from its restart.pt (copied out of its
    directory, as a committed file would be) in ``tmp_path/name``."""
    file = tmp_path / f"{source}-restart.pt"
    if not file.exists():
        shutil.copyfile(tmp_path / source / "restart.pt", file)
    explicit = {"train.refill_steps": refill, "train.total_steps": total}
    return branch(file, tmp_path / name, explicit=explicit)


@pytest.fixture
def stopped_run(tmp_path):
    result = train(config_from_dict(tiny_dict(total_steps=230)), tmp_path / "run")
    assert result.steps == 230 and result.episodes >= 2
    return tmp_path / "run"


def test_restart_file_is_the_state_without_replay_and_with_the_metrics(stopped_run):
    state = load_checkpoint(stopped_run / "state.pt")
    restart = load_checkpoint(stopped_run / "restart.pt")
    assert state["buffer"]["size"] == 230 and restart["buffer"]["size"] == 0
    assert restart["episode"]["obs"] is None and state["episode"]["obs"] is not None
    assert restart["restart"]["step"] == 230
    assert restart_metrics_text(restart["restart"]) == (stopped_run / "metrics.csv").read_text()
    for net in ("actor", "critic", "critic_target"):
        for key, value in state["agent"][net].items():
            assert torch.equal(value, restart["agent"][net][key]), (net, key)
    for opt in ("actor_opt", "critic_opt"):  # settings kept, moments left out (adam_moments.py)
        assert state["agent"][opt]["state"] and restart["agent"][opt]["state"] == {}
        assert restart["agent"][opt]["param_groups"] == state["agent"][opt]["param_groups"]
    alpha_moments = state["agent"]["alpha_opt"]["state"][0]
    assert torch.equal(
        restart["agent"]["alpha_opt"]["state"][0]["exp_avg"], alpha_moments["exp_avg"]
    )
    assert restart["counters"] == state["counters"]
    assert torch.equal(restart["rng"]["torch"], state["rng"]["torch"])


def test_restart_refills_without_updates_then_learns(tmp_path, stopped_run):
    result = restarted(tmp_path, refill=60, total=400)
    assert result.steps == 400
    state = load_checkpoint(tmp_path / "restarted" / "state.pt")
    # updates from step 231 to 400 in the source run; here 290 (= 230 + 60) is the last without
    assert state["agent"]["updates"] == (230 - 100) + (400 - 290)
    assert state["counters"]["refill_until"] == 290
    assert state["buffer"]["size"] == 400 - 230  # what it has seen since the restart, alone
    # the moments were estimated from the refilled buffer, then 110 updates ran: Adam's t
    # counts K = 1 / (1 - b2) = 1,000 steps of size zero and 110 updates
    steps = {float(m["step"]) for m in state["agent"]["critic_opt"]["state"].values()}
    assert steps == {1000.0 + 110}
    rows = read_metrics(tmp_path / "restarted" / "metrics.csv")
    source_rows = read_metrics(stopped_run / "metrics.csv")
    assert rows[: len(source_rows)] == source_rows
    assert all(int(r["step"]) > 230 for r in rows[len(source_rows) :])
    origin = (tmp_path / "restarted" / "branched_from.txt").read_text()
    assert origin.startswith("restart file ") and origin.endswith("at step 230\n")
    # the source run is only read
    assert load_checkpoint(stopped_run / "state.pt")["counters"]["step"] == 230


def test_restart_is_reproducible_and_differs_from_the_run_with_its_buffer(tmp_path, stopped_run):
    restarted(tmp_path, "a", refill=60)
    restarted(tmp_path, "b", refill=60)
    a = load_checkpoint(tmp_path / "a" / "state.pt")
    b = load_checkpoint(tmp_path / "b" / "state.pt")
    assert_states_equal(
        {k: v for k, v in a.items() if k != "path"}, {k: v for k, v in b.items() if k != "path"}
    )
    resume(stopped_run, total_steps=400)
    full = load_checkpoint(stopped_run / "state.pt")["agent"]["actor"]
    assert any(not torch.equal(full[k], a["agent"]["actor"][k]) for k in full)


def test_a_restarted_run_resumes_exactly_inside_its_refill(tmp_path, stopped_run):
    restarted(tmp_path, "straight", refill=100, total=400)
    restarted(tmp_path, "split", refill=100, total=280)  # stops inside the refill (to 330)
    split_state = load_checkpoint(tmp_path / "split" / "state.pt")
    assert split_state["counters"]["step"] == 280 and split_state["counters"]["refill_until"] == 330
    resume(tmp_path / "split", total_steps=400)
    a = load_checkpoint(tmp_path / "straight" / "state.pt")
    b = load_checkpoint(tmp_path / "split" / "state.pt")
    skip = ("/counters/wall_time", "/config/train/total_steps")
    assert_states_equal(
        {k: v for k, v in a.items() if k != "path"},
        {k: v for k, v in b.items() if k != "path"},
        skip,
    )


def test_restart_file_is_refused_where_a_run_directory_is_expected(tmp_path, stopped_run):
    file = tmp_path / "restart.pt"
    shutil.copyfile(stopped_run / "restart.pt", file)
    with pytest.raises(UserError, match=r"restart file .* --into DIR"):
        resume(file, total_steps=400)
    assert not (tmp_path / "state.pt").exists()
    with pytest.raises(UserError, match="a branch needs --config"):
        branch(stopped_run, tmp_path / "b")


def test_a_state_with_replay_posing_as_a_restart_file_is_refused(tmp_path, stopped_run):
    state = load_checkpoint(stopped_run / "state.pt")
    state.pop("path")
    state["restart"] = {"step": 230, "metrics_csv": ""}
    torch.save(state, tmp_path / "bad.pt")
    with pytest.raises(UserError, match="'buffer' should be empty in a restart file"):
        load_checkpoint(tmp_path / "bad.pt")
    state["buffer"] = load_checkpoint(stopped_run / "restart.pt")["buffer"]
    state["restart"]["step"] = 7
    torch.save(state, tmp_path / "bad.pt")
    with pytest.raises(UserError, match="'restart.step' should be counters.step"):
        load_checkpoint(tmp_path / "bad.pt")
    state["restart"] = {"step": 230, "metrics_csv_zlib": b"not zlib"}
    torch.save(state, tmp_path / "bad.pt")
    with pytest.raises(UserError, match="'restart.metrics_csv_zlib' is not zlib-packed text"):
        load_checkpoint(tmp_path / "bad.pt")


def test_refill_steps_is_validated_and_may_change_in_a_branch(tmp_path, stopped_run):
    with pytest.raises(UserError, match="'train.refill_steps' expects a non-negative integer"):
        config_from_dict(tiny_dict(refill_steps=-1))
    with pytest.raises(UserError, match="'agent.gamma' is 0.9"):
        branch(tmp_path / "run" / "restart.pt", tmp_path / "x", overrides=["agent.gamma=0.9"])


def test_cli_continues_a_restart_file_and_info_names_it(tmp_path, stopped_run, capsys):
    from .test_cli import run_cli

    file = tmp_path / "committed.pt"
    shutil.copyfile(stopped_run / "restart.pt", file)
    code, out, err = run_cli(["info", file], capsys)
    assert code == 0, err
    assert "restart file" in out and "0 transitions" in out
    assert "left out (estimated again after the refill)" in out
    code, out, err = run_cli(["info", stopped_run / "state.pt"], capsys)
    assert code == 0 and re.search(r"adam moments\s+\S\s+kept", out), out
    code, out, err = run_cli(["resume", file], capsys)
    assert code == 2 and "--into DIR" in err and "Traceback" not in err
    into = tmp_path / "again"
    args = ["resume", file, "--into", into, "--steps", 300, "--set", "train.refill_steps=40"]
    code, out, err = run_cli(args, capsys)
    assert code == 0, err
    state = load_checkpoint(into / "state.pt")
    assert state["counters"]["step"] == 300 and state["counters"]["refill_until"] == 270
    assert state["config"]["train"]["refill_steps"] == 40


@pytest.mark.parametrize("source", ["restart.pt", "state.pt"])
def test_a_budget_below_the_runs_step_is_refused_before_the_directory_is_made(
    tmp_path, stopped_run, source
):
    explicit = {"train.total_steps": 100}
    overrides = None if source == "restart.pt" else ["train.keep_policies=true"]
    refused = r"--steps \(train.total_steps\) 100: the run is at step 230"
    with pytest.raises(UserError, match=refused):
        branch(stopped_run / source, tmp_path / "x", overrides=overrides, explicit=explicit)
    assert not (tmp_path / "x").exists()
    with pytest.raises(UserError, match="--steps 100: the run is at step 230"):
        resume(stopped_run, total_steps=100)
