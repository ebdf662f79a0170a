"""record, plot, export, info and curriculum, end to end through the CLI."""

import csv
import os

import imageio.v2 as imageio
import numpy as np
import pytest
import torch
import yaml
from PIL import Image, ImageSequence

from bipedal_cli.checkpoint import actor_from_checkpoint, load_checkpoint

from .conftest import tiny_dict
from .test_cli import run_cli


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    from bipedal_cli.config import config_from_dict
    from bipedal_cli.train import train

    run = tmp_path_factory.mktemp("cmd") / "run"
    train(config_from_dict(tiny_dict(total_steps=300, eval_every=150)), run)
    return run


def test_record_mp4_reads_back_with_expected_frames(tmp_path, trained, capsys):
    out = tmp_path / "walk.mp4"
    code, stdout, err = run_cli(["record", trained, "--out", out, "--seed", 3], capsys)
    assert code == 0, err
    length = int(stdout.split("return")[1].split(",")[1].split("steps")[0])
    reader = imageio.get_reader(out)
    meta = reader.get_meta_data()
    frames = [f for f in reader]
    assert meta["codec"] == "h264" and meta["pix_fmt"].startswith("yuv420p")
    assert meta["fps"] == 50
    assert len(frames) == length + 1  # the reset frame plus one per step
    assert frames[0].shape == (400, 600, 3)
    assert not all(np.array_equal(frames[0], f) for f in frames[1:])
    assert f"wrote {out}" in stdout.replace("\n", "")


def test_record_gif_is_downscaled_and_subsampled(tmp_path, trained, capsys):
    out = tmp_path / "walk.gif"
    code, stdout, err = run_cli(["record", trained, "--out", out, "--episodes", 2], capsys)
    assert code == 0, err
    frames = imageio.mimread(out, memtest=False)
    assert frames[0].shape[:2] == (200, 300)
    lengths = [
        int(line.split(", ")[1].split()[0])
        for line in stdout.splitlines()
        if line.startswith("episode seed")
    ]
    assert len(lengths) == 2
    # Every 2nd frame at 25 fps (40 ms each). Pillow merges identical consecutive frames into
    # one with their durations added, so count playing time, not frames.
    with Image.open(out) as gif:
        durations = [frame.info["duration"] for frame in ImageSequence.Iterator(gif)]
    assert len(frames) == len(durations) <= sum(n // 2 + 1 for n in lengths)
    assert sum(durations) == pytest.approx(40 * sum(n // 2 + 1 for n in lengths))


def test_plot_overlays_runs_and_train_wrote_its_own(tmp_path, trained, capsys):
    assert (trained / "learning_curve.png").stat().st_size > 10_000
    out = tmp_path / "curves.svg"
    code, _, err = run_cli(
        ["plot", trained, trained, "--label", "a", "--label", "a", "--aggregate", "--out", out],
        capsys,
    )
    assert code == 0, err
    text = out.read_text()
    assert text.startswith("<?xml") and "mean of 2 runs" in text


def test_plot_zooms_in_and_smooths_over_a_chosen_window(tmp_path, trained, capsys):
    out = tmp_path / "zoom.svg"
    args = ["plot", trained, "--window", 3, "--since", 60, "--out", out]
    code, _, err = run_cli(args, capsys)
    assert code == 0, err
    assert "moving mean over 3 episodes" in out.read_text()
    code, _, err = run_cli(["plot", trained, "--window", 0, "--out", tmp_path / "w.svg"], capsys)
    assert code == 2 and "--window 0" in err


def test_plot_stops_at_until_so_unequal_runs_compare_at_equal_steps(tmp_path, trained, capsys):
    from bipedal_cli.plotting import in_window

    steps = np.array([0, 10, 59, 60, 61, 300])
    assert in_window(steps, 10, 60).tolist() == [False, True, True, True, False, False]
    assert in_window(steps, 0, np.inf).all()
    out = tmp_path / "cut.svg"
    code, _, err = run_cli(["plot", trained, "--since", 10, "--until", 60, "--out", out], capsys)
    assert code == 0, err
    code, _, err = run_cli(["plot", trained, "--since", 60, "--until", 60, "--out", out], capsys)
    assert code == 2 and "--until 60" in err and len(err.strip().splitlines()) == 1


def test_export_gives_the_checkpoints_actions_with_torch_alone(tmp_path, trained, capsys):
    out = tmp_path / "policy.pt2"
    code, _, err = run_cli(["export", trained / "policy.pt", "--out", out], capsys)
    assert code == 0, err
    program = torch.export.load(str(out)).module()
    actor, _ = actor_from_checkpoint(load_checkpoint(trained / "policy.pt"))
    for batch in (1, 5, 64):
        obs = torch.randn(batch, 24)
        actions = program(obs)
        assert actions.shape == (batch, 4)
        assert torch.allclose(actions, actor.deterministic(obs), atol=1e-6)


def info_rows(text):
    """``bipedal info``'s table as {row name: value}."""
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip("│ ").split("│")]
        if len(cells) == 2 and cells[0]:
            rows[cells[0]] = cells[1]
    return rows


def test_info_describes_both_kinds_of_checkpoint(trained, capsys):
    state = load_checkpoint(trained / "state.pt")
    code, out, err = run_cli(["info", trained / "policy.pt"], capsys)
    assert code == 0, err
    rows = info_rows(out)
    assert rows["kind"] == "policy (bipedal-policy v1)"
    assert rows["env"] == "BipedalWalker-v3" and rows["obs / action size"] == "24 / 4"
    assert rows["steps"] == "300" and rows["episodes"] == str(state["counters"]["episodes"])
    assert rows["seed"] == "3"
    assert rows["last eval"].startswith("episodes 2, mean ")
    code, out, err = run_cli(["info", trained / "state.pt"], capsys)
    assert code == 0, err
    rows = info_rows(out)
    assert rows["kind"] == "training state (bipedal-train-state v1)"
    assert rows["steps"] == "300"
    assert rows["replay buffer"] == f"{int(state['buffer']['size']):,} transitions"


def test_output_errors(tmp_path, trained, capsys):
    existing = tmp_path / "exists.mp4"
    existing.write_bytes(b"keep me")
    empty_run = tmp_path / "empty"
    empty_run.mkdir()
    cases = [
        (["record", trained, "--out", tmp_path / "walk.avi"], "--out"),
        (["record", trained, "--out", existing], "--force"),
        (["record", trained, "--out", tmp_path / "missing" / "a.mp4"], "does not exist"),
        (["plot", empty_run, "--out", tmp_path / "c.png"], "metrics.csv"),
        (["plot", trained, "--out", tmp_path / "c.jpg"], "--out"),
        (["export", trained, "--out", tmp_path / "p.onnx"], "--out"),
        (["info", tmp_path / "nothing.pt"], "nothing.pt"),
        (["curriculum", "--replay", "maybe"], "curriculum.replay"),
        (["record", trained, "--out", tmp_path / "f.mp4", "--fps", 0], "--fps"),
        (["plot", tmp_path / "nowhere", "--out", tmp_path / "c2.png"], "nowhere"),
        (["plot", trained, "--metric", "wings", "--out", tmp_path / "c3.png"], "--metric"),
    ]
    if os.path.isdir("/proc"):  # refuses new files even to root, whose permission bits all pass
        cases.append((["record", trained, "--out", "/proc/a.mp4"], "/proc is not writable"))
    for args, needle in cases:
        code, _, err = run_cli(args, capsys)
        assert code == 2 and len(err.strip().splitlines()) == 1 and needle in err, (args, err)
    assert existing.read_bytes() == b"keep me"


def test_curriculum_runs_walker_then_hardcore_with_one_agent(tmp_path, capsys):
    data = tiny_dict(eval_every=100)
    data["train"]["solved_threshold"] = -1000.0  # each stage is "solved" at its first evaluation
    data["curriculum"] = {"walker_steps": 400, "hardcore_steps": 150, "replay": "keep"}
    cfg_path = tmp_path / "cur.yaml"
    cfg_path.write_text(yaml.safe_dump(data))
    run = tmp_path / "cur"
    code, out, err = run_cli(["curriculum", "--config", cfg_path, "--run-dir", run], capsys)
    assert code == 0, err
    state = load_checkpoint(run / "state.pt")
    stages = state["curriculum"]["finished"]
    assert [s["env"] for s in stages] == ["BipedalWalker-v3", "BipedalWalkerHardcore-v3"]
    assert stages[0]["steps"] == 100 and stages[0]["stopped"] == "solved"
    assert stages[1]["steps"] == 100 and stages[0]["full_eval"]["solved"]
    with open(run / "metrics.csv") as f:
        rows = list(csv.DictReader(f))
    assert {r["stage"] for r in rows} == {"BipedalWalker-v3", "BipedalWalkerHardcore-v3"}
    assert "BipedalWalkerHardcore-v3" in out and "stage" in out
    assert state["env"] == "BipedalWalkerHardcore-v3"
    assert int(state["buffer"]["size"]) == 200  # replay: keep


def test_curriculum_resume_continues_in_the_current_stage(tmp_path):
    from bipedal_cli.config import config_from_dict
    from bipedal_cli.curriculum import continue_curriculum, new_curriculum_trainer, start_curriculum
    from bipedal_cli.reporting import NullReporter
    from bipedal_cli.resume import resume

    from .test_train import assert_states_equal

    data = tiny_dict(eval_every=0)
    data["curriculum"] = {"walker_steps": 120, "hardcore_steps": 80, "replay": "clear"}

    class StopInStageTwo(NullReporter):
        trainer = None

        def update(self, snapshot):
            if snapshot["step"] >= 150:  # stage 2 started at step 120
                self.trainer.request_stop()

    straight = start_curriculum(config_from_dict(data), tmp_path / "straight")
    assert [s["steps"] for s in straight.stages] == [120, 80]

    reporter = StopInStageTwo()
    reporter.trainer = new_curriculum_trainer(config_from_dict(data), tmp_path / "cut", reporter)
    cut = continue_curriculum(reporter.trainer)
    assert cut.stopped == "interrupted" and [s["env"] for s in cut.stages] == ["BipedalWalker-v3"]
    mid = load_checkpoint(tmp_path / "cut" / "state.pt")
    assert mid["curriculum"]["stage"] == 1 and mid["env"] == "BipedalWalkerHardcore-v3"
    assert 150 <= mid["counters"]["step"] < 200

    finished = resume(tmp_path / "cut")
    assert [s["steps"] for s in finished.stages] == [120, 80]
    a = load_checkpoint(tmp_path / "straight" / "state.pt")
    b = load_checkpoint(tmp_path / "cut" / "state.pt")
    assert int(b["buffer"]["size"]) == 80  # replay: clear emptied it at the switch
    assert_states_equal(
        {k: v for k, v in a.items() if k not in ("path", "curriculum")},
        {k: v for k, v in b.items() if k not in ("path", "curriculum")},
    )
