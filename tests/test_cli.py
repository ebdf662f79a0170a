import json
import signal
import subprocess
import sys
import time

import pytest
import torch
import yaml

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.cli import main

from .conftest import tiny_dict


def run_cli(args, capsys):
    """Run ``bipedal ARGS`` in-process; return (exit code, stdout, stderr)."""
    code = 0
    try:
        main([str(a) for a in args])
    except SystemExit as exc:
        code = exc.code or 0
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture
def tiny_yaml(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(yaml.safe_dump(tiny_dict(total_steps=150)))
    return path


@pytest.fixture
def trained_run(tmp_path, tiny_yaml, capsys):
    run = tmp_path / "run"
    code, out, err = run_cli(["train", "--config", tiny_yaml, "--run-dir", run], capsys)
    assert code == 0, err
    return run


def test_train_then_resume_then_eval_json(tmp_path, trained_run, capsys):
    assert (trained_run / "state.pt").exists() and (trained_run / "policy.pt").exists()
    assert load_checkpoint(trained_run / "state.pt")["counters"]["step"] == 150
    code, out, err = run_cli(["resume", trained_run, "--steps", 200], capsys)
    assert code == 0, err
    assert load_checkpoint(trained_run / "state.pt")["counters"]["step"] == 200

    report = tmp_path / "eval.json"
    code, out, err = run_cli(
        [
            "eval",
            trained_run / "policy.pt",
            "--episodes",
            3,
            "--seed",
            7,
            "--json",
            report,
            "--workers",
            1,
        ],
        capsys,
    )
    assert code == 0, err
    data = json.loads(report.read_text())
    returns = [e["ret"] for e in data["episodes"]]
    assert [e["seed"] for e in data["episodes"]] == [7, 8, 9]
    assert data["summary"]["mean"] == pytest.approx(sum(returns) / 3)
    assert data["summary"]["min"] == pytest.approx(min(returns))
    assert data["summary"]["solved"] is False
    assert data["summary"]["machine"].endswith(" kernels)")  # the CPU that played them
    assert "not solved" in out and f"{data['summary']['mean']:.1f}" in out
    # the same seeds give the same returns, whichever process runs them
    again = tmp_path / "again.json"
    run_cli(
        ["eval", trained_run, "--episodes", 3, "--seed", 7, "--json", again, "--workers", 2], capsys
    )
    assert [e["ret"] for e in json.loads(again.read_text())["episodes"]] == returns


def test_train_set_and_seed_options_reach_the_config(tmp_path, tiny_yaml, capsys):
    run = tmp_path / "r"
    code, _, err = run_cli(
        [
            "train",
            "--config",
            tiny_yaml,
            "--set",
            "agent.lr=0.001",
            "--seed",
            11,
            "--steps",
            20,
            "--run-dir",
            run,
        ],
        capsys,
    )
    assert code == 0, err
    cfg = yaml.safe_load((run / "config.yaml").read_text())
    assert cfg["agent"]["lr"] == 0.001 and cfg["seed"] == 11 and cfg["train"]["total_steps"] == 20


def bad_inputs(tmp_path, run):
    garbage = tmp_path / "garbage.pt"
    garbage.write_bytes(b"\x00" * 100)
    truncated = tmp_path / "truncated.pt"
    truncated.write_bytes((run / "policy.pt").read_bytes()[:5000])
    wrong_dims = tmp_path / "wrong_dims.pt"
    data = torch.load(run / "policy.pt", weights_only=True)
    data["obs_dim"] = 10
    torch.save(data, wrong_dims)
    bad_yaml = tmp_path / "bad.yaml"
    bad_yaml.write_text("agent: [1, 2\n")
    wrong_type = tmp_path / "wrong_type.yaml"
    wrong_type.write_text("agent:\n  batch_size: lots\n")
    return [
        (["eval", tmp_path / "missing.pt"], "missing.pt"),
        (["eval", garbage], "garbage.pt"),
        (["eval", truncated], "truncated.pt"),
        (["eval", wrong_dims], "wrong_dims.pt"),
        (["eval", run / "policy.pt", "--env", "moon"], "--env"),
        (["eval", run / "policy.pt", "--episodes", 0], "--episodes"),
        (["eval", run / "policy.pt", "--json", tmp_path / "no" / "dir.json"], "--json"),
        (["train", "--config", tmp_path / "nope.yaml"], "nope.yaml"),
        (["train", "--config", bad_yaml], "bad.yaml"),
        (["train", "--config", wrong_type], "agent.batch_size"),
        (["train", "--set", "agent.wings=2"], "agent.wings"),
        (["train", "--set", "novalue"], "--set"),
        (["train", "--env", "moon"], "--env"),
        (
            ["train", "--device", "cuda"]
            if not torch.cuda.is_available()
            else ["train", "--device", "tpu"],
            "--device",
        ),
        (["train", "--run-dir", run], str(run)),
        (["resume", tmp_path / "nothing"], "nothing"),
        (["resume", run / "policy.pt"], "policy.pt"),
        (["eval"], "CKPT"),
    ]


def test_bad_input_gives_one_line_error_and_exit_2(tmp_path, trained_run, capsys):
    before = {p: p.read_bytes() for p in trained_run.iterdir()}
    for args, needle in bad_inputs(tmp_path, trained_run):
        code, out, err = run_cli(args, capsys)
        lines = err.strip().splitlines()
        assert code == 2, (args, err)
        assert len(lines) == 1 and needle in lines[0], (args, err)
        assert "Traceback" not in err + out
    after = {p: p.read_bytes() for p in trained_run.iterdir()}
    assert before == after, "bad input must not touch the run"


def test_console_script_reports_errors_without_traceback(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "bipedal_cli", "eval", str(tmp_path / "missing.pt")],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert proc.returncode == 2
    assert proc.stderr.strip() == f"bipedal: error: CKPT {tmp_path / 'missing.pt'}: no such file"


@pytest.mark.parametrize("signum, status", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_stop_signal_saves_a_checkpoint_and_exits_with_128_plus_its_number(
    tmp_path, tiny_yaml, signum, status
):
    """Ctrl-C and SIGTERM (schedulers, timeout, a shutdown) both checkpoint and stop."""
    run = tmp_path / "run"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "bipedal_cli",
            "train",
            "--config",
            str(tiny_yaml),
            "--steps",
            "1000000",
            "--run-dir",
            str(run),
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.time() + 120
    metrics = run / "metrics.csv"
    while time.time() < deadline and (not metrics.exists() or metrics.read_text().count("\n") < 3):
        time.sleep(0.2)
    proc.send_signal(signum)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == status, err
    assert "interrupted, checkpoint saved" in out
    state = load_checkpoint(run / "state.pt")
    assert 0 < state["counters"]["step"] < 1_000_000
    assert load_checkpoint(run / "policy.pt")["meta"]["steps"] == state["counters"]["step"]


def test_installed_console_script_lists_every_command():
    """`bipedal --help` from the installed entry point, in a fresh process: what a new user runs
    first. It fails when a module the CLI imports is missing from the environment."""
    from pathlib import Path

    script = Path(sys.executable).parent / "bipedal"
    assert script.exists(), f"no console script beside {sys.executable}: install with pip first"
    proc = subprocess.run(
        [str(script), "--help"],
        capture_output=True,
        text=True,
        timeout=120,
        env={"COLUMNS": "200", "PATH": str(script.parent)},
    )
    assert proc.returncode == 0, proc.stderr
    commands = ("train", "resume", "curriculum", "eval", "select", "record", "plot", "export")
    for command in (*commands, "info", "sweep"):
        assert f" {command} " in proc.stdout, f"`{command}` missing from bipedal --help"
