"""Policy files and training states record the machine they were written on, because a seed
fixes a run's bits only on one kind of CPU (session 33: an Intel AVX512 machine parts from the
AMD AVX2 runs at the first update). A resume on another kind of machine says so once;
benchmarks/same_policy.py names both machines when they differ, without calling that a
difference."""

from pathlib import Path

import pytest
import torch

from bipedal_cli.checkpoint import load_checkpoint
from bipedal_cli.config import config_from_dict
from bipedal_cli.devices import machine_summary
from bipedal_cli.errors import UserError
from bipedal_cli.reporting import NullReporter
from bipedal_cli.resume import resume
from bipedal_cli.train import train

from .conftest import load_benchmark, tiny_dict

same_policy = load_benchmark("same_policy")
SHIPPED_ROOT = Path(__file__).resolve().parent.parent


class Notes(NullReporter):
    def __init__(self) -> None:
        self.lines: list[str] = []

    def log(self, text: str) -> None:
        self.lines.append(text)


def _machine_notes(lines: list[str]) -> list[str]:
    return [line for line in lines if "this state was saved on" in line]


def test_a_run_records_its_machine_and_notes_a_resume_elsewhere(tmp_path):
    run = tmp_path / "run"
    train(config_from_dict(tiny_dict(total_steps=120)), run)
    here = machine_summary(torch.device("cpu"))
    assert here.endswith(f"({torch.backends.cpu.get_cpu_capability()} kernels)")
    assert load_checkpoint(run / "state.pt")["machine"] == here
    assert load_checkpoint(run / "policy.pt")["meta"]["machine"] == here

    same_machine = Notes()
    resume(run, total_steps=160, reporter=same_machine)
    assert _machine_notes(same_machine.lines) == []

    state = torch.load(run / "state.pt", map_location="cpu", weights_only=False)
    state["machine"] = "AMD EPYC 7B13 (AVX2 kernels)"
    torch.save(state, run / "state.pt")
    elsewhere = Notes()
    resume(run, total_steps=200, reporter=elsewhere)
    assert _machine_notes(elsewhere.lines) == [
        f"note: this state was saved on AMD EPYC 7B13 (AVX2 kernels); this is {here}. The run "
        "goes on, but will not match one that stayed on the first machine bit for bit"
    ]


def test_a_damaged_machine_in_a_state_is_a_one_line_error(tmp_path):
    train(config_from_dict(tiny_dict(total_steps=60)), tmp_path / "run")
    state = torch.load(tmp_path / "run" / "state.pt", map_location="cpu", weights_only=False)
    state["machine"] = 5
    torch.save(state, tmp_path / "run" / "state.pt")
    with pytest.raises(UserError, match=r"state\.pt.*machine") as err:
        load_checkpoint(tmp_path / "run" / "state.pt")
    assert "\n" not in str(err.value)


def test_same_policy_names_two_machines_without_calling_them_a_difference(tmp_path, capsys):
    run = tmp_path / "run"
    train(config_from_dict(tiny_dict(total_steps=60)), run)
    data = torch.load(run / "policy.pt", map_location="cpu", weights_only=True)
    data["meta"]["machine"] = "AMD EPYC 7B13 (AVX2 kernels)"
    torch.save(data, tmp_path / "copy.pt")

    assert same_policy.main([str(run / "policy.pt"), str(tmp_path / "copy.pt")]) == 0
    last = capsys.readouterr().out.splitlines()[-1]
    here = machine_summary(torch.device("cpu"))
    assert last == f"written on {here} and on AMD EPYC 7B13 (AVX2 kernels)"


def test_benchmark_records_of_one_minute_do_not_overwrite_each_other(tmp_path):
    record = load_benchmark("record")
    first = record.unused_path(tmp_path / "results", "device_speed-2026-12-05-1036")
    assert first.name == "device_speed-2026-12-05-1036.json"
    first.write_text("{}")
    second = record.unused_path(tmp_path / "results", "device_speed-2026-12-05-1036")
    assert second.name == "device_speed-2026-12-05-1036-2.json"
    assert machine_summary(torch.device("cpu")).startswith(record.machine()["cpu"])


def test_the_shipped_policy_on_two_cpus_shares_one_fall_and_no_return(capsys, monkeypatch):
    fall_overlap = load_benchmark("fall_overlap")
    reports = [
        SHIPPED_ROOT / "checkpoints" / "bipedal_hardcore.eval.json",  # the report's machine
        SHIPPED_ROOT / "docs" / "runs" / "hardcore-shipped-eval-session33.json",  # Intel AVX512
    ]
    monkeypatch.setattr("sys.argv", ["fall_overlap.py", *map(str, reports)])
    fall_overlap.main()
    lines = capsys.readouterr().out.splitlines()
    assert lines[3] == (
        "  seeds: both [31], only the first [2, 46, 55], only the second [11, 36, 65]; "
        "returns equal to 1e-6: 0 of 100"
    )
