"""Run directories that survive misuse, and one line for every bad input (issue 13).

Every case: exit code 2, one line on stderr naming the file or option, and no file of the run
written (the bytes and mtimes of the run directory are compared before and after)."""

import errno
import math
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest
import torch
import yaml

from bipedal_cli import checkpoint as ckpt_mod
from bipedal_cli.checkpoint import atomic_save, load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.rundir import lock_run_dir
from bipedal_cli.train import train

from .conftest import tiny_dict
from .test_cli import run_cli


def snapshot(directory):
    return {
        p.name: (p.read_bytes(), p.stat().st_mtime_ns)
        for p in sorted(directory.iterdir())
        if p.is_file() and not p.is_symlink() and p.name != ".lock"
    }


@pytest.fixture(scope="module")
def pristine(tmp_path_factory):
    run = tmp_path_factory.mktemp("safety") / "run"
    train(config_from_dict(tiny_dict(total_steps=150)), run)
    return run


@pytest.fixture
def run(tmp_path, pristine):
    copy = tmp_path / "run"
    shutil.copytree(pristine, copy)
    return copy


def expect_one_line_error(args, capsys, *needles, code=2):
    status, out, err = run_cli(args, capsys)
    assert status == code, (args, out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("bipedal: error:"), err
    for needle in needles:
        assert str(needle) in lines[0], (needle, lines[0])
    return lines[0]


def edit_checkpoint(path, edit):
    data = torch.load(path, weights_only=True)
    edit(data)
    torch.save(data, path)  # a plain save: the test writes a damaged file on purpose


# --------------------------------------------------------------- a run cannot be damaged


@pytest.mark.parametrize("steps, needle", [(-1, "--steps -1"), (100, "at step 150")])
def test_resume_refuses_a_budget_below_the_run_and_writes_nothing(run, capsys, steps, needle):
    before = snapshot(run)
    expect_one_line_error(["resume", run, "--steps", steps], capsys, needle)
    assert snapshot(run) == before
    status, _, err = run_cli(["resume", run, "--steps", 160], capsys)  # the run still works
    assert status == 0, err


def test_a_second_process_on_a_run_dir_is_refused_with_the_holders_pid(run, capsys):
    before = snapshot(run)
    with lock_run_dir(run):
        expect_one_line_error(["resume", run, "--steps", 200], capsys, run, f"PID {os.getpid()}")
        expect_one_line_error(
            ["train", "--config", run / "config.yaml", "--run-dir", run], capsys, run
        )
    assert snapshot(run) == {k: v for k, v in before.items()}


def test_a_lock_left_by_a_killed_process_does_not_block_resume(run, capsys):
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time, pathlib\nfrom bipedal_cli.rundir import lock_run_dir\n"
            f"with lock_run_dir(pathlib.Path({str(run)!r})):\n"
            "    print('locked', flush=True)\n    time.sleep(600)\n",
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    assert holder.stdout.readline().strip() == "locked"
    expect_one_line_error(["resume", run, "--steps", 200], capsys, f"PID {holder.pid}")
    holder.send_signal(signal.SIGKILL)
    holder.wait(timeout=30)
    status, _, err = run_cli(["resume", run, "--steps", 200], capsys)
    assert status == 0, err
    assert load_checkpoint(run / "state.pt")["counters"]["step"] == 200


def test_a_directory_killed_before_its_first_checkpoint_can_be_trained_again(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.yaml").write_text(yaml.safe_dump(tiny_dict()))  # what such a kill leaves
    expect_one_line_error(["resume", run], capsys, "bipedal train --run-dir")
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(tiny_dict(total_steps=30)))
    status, _, err = run_cli(["train", "--config", cfg, "--run-dir", run], capsys)
    assert status == 0, err


def test_every_run_writes_a_step_zero_checkpoint_before_its_metrics(tmp_path):
    from bipedal_cli.train import Trainer

    trainer = Trainer(config_from_dict(tiny_dict(total_steps=0)), tmp_path / "run")
    trainer.run()
    assert load_checkpoint(tmp_path / "run" / "state.pt")["counters"]["step"] == 0


def test_a_symlinked_config_is_replaced_not_written_through(run, tmp_path, capsys):
    outside = tmp_path / "precious.yaml"
    outside.write_text("do not touch\n")
    (run / "config.yaml").unlink()
    (run / "config.yaml").symlink_to(outside)
    status, _, err = run_cli(["resume", run, "--steps", 160], capsys)
    assert status == 0, err
    assert outside.read_text() == "do not touch\n"
    assert not (run / "config.yaml").is_symlink()
    assert yaml.safe_load((run / "config.yaml").read_text())["train"]["total_steps"] == 160


def test_a_symlinked_metrics_file_is_refused(run, tmp_path, capsys):
    outside = tmp_path / "precious.csv"
    outside.write_text("do not touch\n")
    (run / "metrics.csv").unlink()
    (run / "metrics.csv").symlink_to(outside)
    expect_one_line_error(["resume", run, "--steps", 160], capsys, "metrics.csv")
    assert outside.read_text() == "do not touch\n"


def test_a_full_disk_is_one_line_and_keeps_the_previous_checkpoint(run, capsys, monkeypatch):
    state_before = (run / "state.pt").read_bytes()
    real_save = torch.save

    def full_disk(obj, f, *args, **kwargs):
        real_save(obj, f, *args, **kwargs)
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(ckpt_mod.torch, "save", full_disk)
    expect_one_line_error(["resume", run, "--steps", 200], capsys, "state.pt", "No space")
    monkeypatch.undo()
    assert (run / "state.pt").read_bytes() == state_before
    assert not list(run.glob(".*.tmp*"))


def test_stale_temporaries_of_a_killed_save_are_removed_at_the_next_start(run, capsys):
    stale = run / ".state.k1ll3d.tmp.pt"
    stale.write_bytes(b"PK half a checkpoint")
    status, _, err = run_cli(["resume", run, "--steps", 160], capsys)
    assert status == 0, err
    assert not stale.exists()


def test_a_torn_last_metrics_row_is_dropped_on_resume(run, capsys):
    with open(run / "metrics.csv", "a") as f:
        f.write("episode,BipedalWalker-v3,14")  # power lost mid-row
    status, _, err = run_cli(["resume", run, "--steps", 200], capsys)
    assert status == 0, err
    text = (run / "metrics.csv").read_text()
    assert "BipedalWalker-v3,14\n" not in text and not text.count(",14,") > 1


def test_training_that_diverges_stops_with_one_line_and_keeps_the_last_checkpoint(tmp_path, capsys):
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(tiny_dict(total_steps=400, checkpoint_every=100)))
    from bipedal_cli import agent as agent_mod

    real_update = agent_mod.TQCAgent.update

    def poisoned(self, batch):
        metrics = real_update(self, batch)
        if self.updates == 180:  # the actor's weights go NaN after update 180 (step 280)
            self.sync()
            with torch.no_grad():
                next(self.actor.parameters()).fill_(math.nan)
        return metrics

    mp = pytest.MonkeyPatch()
    mp.setattr(agent_mod.TQCAgent, "update", poisoned)
    try:
        line = expect_one_line_error(
            ["train", "--config", cfg, "--run-dir", tmp_path / "run"], capsys, "diverged"
        )
    finally:
        mp.undo()
    assert "step 280" in line
    state = load_checkpoint(tmp_path / "run" / "state.pt")
    assert state["counters"]["step"] == 200


# ------------------------------------------------------------- bad input: one line, exit 2


def damaged_state_cases():
    def drop(key):
        return lambda d: d.pop(key)

    def set_(key, value):
        return lambda d: d.__setitem__(key, value)

    def wrong_shape(d):
        name = next(iter(d["agent"]["actor"]))
        d["agent"]["actor"][name] = torch.zeros(3)

    return [
        ("missing key", drop("buffer"), "'buffer' is missing"),
        ("version not a number", set_("version", "one"), "format version"),
        ("config not a mapping", set_("config", [1, 2]), "'config'"),
        ("wrong weight shape", wrong_shape, "agent.actor"),
        ("huge declared size", set_("obs_dim", 10**9), "obs_dim"),
    ]


@pytest.mark.parametrize("case, edit, needle", damaged_state_cases(), ids=lambda c: str(c)[:20])
def test_resume_of_a_damaged_state_is_one_line(run, capsys, case, edit, needle):
    edit_checkpoint(run / "state.pt", edit)
    before = snapshot(run)
    expect_one_line_error(["resume", run, "--steps", 200], capsys, "state.pt", needle)
    assert snapshot(run) == before


@pytest.mark.parametrize("command", ["eval", "export", "info"])
@pytest.mark.parametrize(
    "edit, needle",
    [
        (lambda d: next(iter(d["actor"].values())).fill_(math.nan), "NaN"),
        (lambda d: d["config"]["agent"].__setitem__("actor_hidden", 10**7), "actor_hidden"),
        (lambda d: d.__setitem__("obs_dim", 10**9), "obs_dim"),
        (lambda d: d.pop("actor"), "'actor' is missing"),
    ],
    ids=["nan-weights", "huge-hidden", "huge-obs", "no-actor"],
)
def test_damaged_policy_is_one_line_in_every_command(run, tmp_path, capsys, command, edit, needle):
    edit_checkpoint(run / "policy.pt", edit)
    args = {"eval": ["--episodes", 1], "export": ["--out", tmp_path / "p.pt2"], "info": []}
    expect_one_line_error([command, run / "policy.pt", *args[command]], capsys, needle)
    assert not (tmp_path / "p.pt2").exists()


@pytest.mark.parametrize(
    "args, needle",
    [
        (["--set", "agent.lr=inf"], "agent.lr"),
        (["--set", "agent.target_entropy=nan"], "agent.target_entropy"),
        (["--set", "train.solved_threshold=nan"], "train.solved_threshold"),
        (["--set", "agent.log_std_min=3"], "agent.log_std_min"),
        (["--seed", -1], "seed"),
        (["--seed", 2**31], "seed"),
        (["--set", "train.eval_seed=-1"], "train.eval_seed"),
        (["--set", "train.threads=100000"], "train.threads"),
        (["--steps", -5], "train.total_steps"),
    ],
)
def test_bad_training_values_are_one_line_and_create_nothing(tmp_path, capsys, args, needle):
    run = tmp_path / "run"
    expect_one_line_error(["train", "--run-dir", run, *args], capsys, needle)
    assert not run.exists()


@pytest.mark.parametrize(
    "args, needle",
    [
        (["eval", "@", "--seed", -5], "--seed"),
        (["eval", "@", "--episodes", 10**9], "--episodes"),
        (["record", "@", "--seed", -1], "--seed"),
        (["record", "@", "--fps", "nan"], "--fps"),
        (["record", "@", "--fps", "inf"], "--fps"),
        (["record", "@", "--frame-step", 0], "--frame-step"),
        (["record", "@", "--scale", 0], "--scale"),
    ],
)
def test_bad_command_options_are_one_line(run, tmp_path, capsys, args, needle):
    args = [run / "policy.pt" if a == "@" else a for a in args]
    if args[0] == "record":
        args += ["--out", tmp_path / "v.mp4"]
    expect_one_line_error(args, capsys, needle)
    assert not (tmp_path / "v.mp4").exists()


def test_a_run_dir_whose_name_is_not_utf8_trains_and_plots(tmp_path, capsys):
    name = os.fsdecode(b"run-\xff\xfe")
    cfg = tmp_path / "tiny.yaml"
    cfg.write_text(yaml.safe_dump(tiny_dict(total_steps=120)))
    status, _, err = run_cli(["train", "--config", cfg, "--run-dir", tmp_path / name], capsys)
    assert status == 0, err
    assert (tmp_path / name / "learning_curve.png").stat().st_size > 1000


def test_atomic_save_reports_the_file_on_torch_write_errors(tmp_path, monkeypatch):
    from bipedal_cli.errors import UserError

    def torch_fails(obj, f, *args, **kwargs):
        raise RuntimeError("[enforce fail at inline_container.cc] unexpected pos 123 vs 456")

    monkeypatch.setattr(ckpt_mod.torch, "save", torch_fails)
    with pytest.raises(UserError, match="x.pt: could not be written") as info:
        atomic_save({"a": 1}, tmp_path / "x.pt")
    assert "\n" not in str(info.value)
    assert not list(tmp_path.iterdir())
    time.sleep(0)
