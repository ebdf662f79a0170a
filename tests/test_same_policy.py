"""benchmarks/same_policy.py, the check of issue 14's item 2 (the shipped policy retrained from
scratch), calls two actors the same only when every tensor has the same bits and the files
record the same place in training; one ulp in one weight, or another policy step, is reported."""

from pathlib import Path

import torch

from bipedal_cli.checkpoint import TRAIN_FORMAT

from .conftest import load_benchmark

same_policy = load_benchmark("same_policy")
SHIPPED = Path(__file__).resolve().parent.parent / "checkpoints" / "bipedal_hardcore.pt"


def _changed_copy(tmp_path: Path, change) -> Path:
    data = torch.load(SHIPPED, map_location="cpu", weights_only=True)
    change(data)
    path = tmp_path / "copy.pt"
    torch.save(data, path)
    return path


def test_a_policy_is_the_same_as_itself(capsys):
    assert same_policy.main([str(SHIPPED), str(SHIPPED)]) == 0
    out = capsys.readouterr().out
    assert out.startswith("7 of 7 actor tensors equal; largest difference 0")
    assert "DIFFERENT" not in out


def test_one_ulp_in_one_weight_is_a_difference(tmp_path, capsys):
    def nudge(data):
        w = data["actor"]["net.b_out"]
        w.view(-1)[3] = torch.nextafter(w.view(-1)[3], torch.tensor(float("inf")))

    copy = _changed_copy(tmp_path, nudge)
    assert same_policy.main([str(SHIPPED), str(copy)]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("6 of 7 actor tensors equal; largest difference ")
    assert 0 < float(out[0].rsplit(" ", 1)[1]) < 1e-6
    assert out[1] == "differ: net.b_out"


def test_the_same_weights_at_another_step_are_reported(tmp_path, capsys):
    copy = _changed_copy(tmp_path, lambda data: data["meta"].update(steps=1760000))
    assert same_policy.main([str(SHIPPED), str(copy)]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].startswith("7 of 7 actor tensors equal")
    assert [line.split()[-1] for line in lines if line.startswith("steps")] == ["DIFFERENT"]


def test_a_training_state_records_its_counters_under_other_names():
    state = {
        "format": TRAIN_FORMAT,
        "config": {"env": "BipedalWalkerHardcore-v3"},
        "counters": {"step": 1740000, "env_steps": 5211833, "episodes": 8263, "wall_time": 9.0},
        "last_eval": {"mean": 308.32357},
        "full_eval": None,
    }
    assert same_policy.counters_of(state) == {
        "env": "BipedalWalkerHardcore-v3",
        "steps": 1740000,
        "env_steps": 5211833,
        "episodes": 8263,
        "last_eval": 308.324,
    }


def test_a_missing_file_is_a_one_line_error(tmp_path, capsys):
    assert same_policy.main([str(SHIPPED), str(tmp_path / "none.pt")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"file 2 {tmp_path / 'none.pt'}: no such file"
