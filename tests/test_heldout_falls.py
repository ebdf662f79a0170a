"""benchmarks/heldout_falls.py puts every run's held-out windows against the shipped policy's
score on the same seeds, and refuses a report that played another policy under its path."""

from pathlib import Path

import pytest

from .conftest import load_benchmark

heldout_falls = load_benchmark("heldout_falls")

SHA = "ab" * 32


def candidate(path, step, mean, falls, sha256="00" * 32):
    held = {"episodes": 200, "mean": mean, "falls": falls, "median": 300.0, "mean_length": 900}
    return {"path": path, "step": step, "sha256": sha256, "held_out": held}


def report():
    return {
        "candidates": [
            candidate(heldout_falls.REFERENCE, 1_740_000, 290.0, 8, SHA),
            candidate("runs/a/policies/step-1500000.pt", 1_500_000, 280.0, 20),
            candidate("runs/a/policies/step-1520000.pt", 1_520_000, 284.0, 10),
            candidate("runs/a/policies/step-1600000.pt", 1_600_000, 295.0, 4),
            candidate("runs/a/policy.pt", 1_612_345, 291.0, 6),
        ]
    }


def test_windows_are_differences_from_the_reference_on_the_same_seeds():
    windows = heldout_falls.against_reference(report(), 100_000, SHA)
    got = [(w.run, w.first_step, w.policies, w.extra_falls, w.extra_return) for w in windows]
    # the reference falls 4 times per 100 (8 in 200) and scores 290.0
    assert got == [
        ("runs/a", 1_500_000, 2, pytest.approx(7.5 - 4.0), pytest.approx(282.0 - 290.0)),
        ("runs/a", 1_600_000, 1, pytest.approx(2.0 - 4.0), pytest.approx(5.0)),
        ("runs/a/policy.pt", 1_612_345, 1, pytest.approx(3.0 - 4.0), pytest.approx(1.0)),
    ]
    assert [w.single_file for w in windows] == [False, False, True]
    label = heldout_falls.row_label(Path("x/hardcore-select-session13.json"), "runs/a/policy.pt")
    assert label == "session13: a"


def test_a_report_that_played_another_policy_under_the_shipped_path_is_refused():
    with pytest.raises(ValueError, match="sha256"):
        heldout_falls.against_reference(report(), 100_000, "cd" * 32)
    without = {"candidates": report()["candidates"][1:]}
    with pytest.raises(ValueError, match="does not play"):
        heldout_falls.against_reference(without, 100_000, SHA)


def test_select_by_run_counts_where_each_window_fell():
    select_by_run = load_benchmark("select_by_run")
    candidates = report()["candidates"]
    candidates[1]["held_out"]["falls_at"] = {"stump": 15, "pit": 5}
    candidates[2]["held_out"]["falls_at"] = {"stump": 6, "stairs": 4}
    windows = select_by_run.summarise(candidates, 100_000)
    got = [(w.run, w.first_step, w.last_step, w.policies, w.falls_at) for w in windows]
    assert got == [
        (heldout_falls.REFERENCE, 1_740_000, 1_740_000, 1, {}),  # a file on its own is its run
        ("runs/a", 1_500_000, 1_520_000, 2, {"stump": 21, "pit": 5, "stairs": 4}),
        ("runs/a", 1_600_000, 1_600_000, 1, {}),  # no falls_at recorded
        ("runs/a/policy.pt", 1_612_345, 1_612_345, 1, {}),
    ]
    assert windows[1].falls_per_100 == pytest.approx((10.0 + 5.0) / 2)
    assert windows[1].mean_return == pytest.approx(282.0)


def test_select_by_run_to_leaves_out_kept_policies_past_a_step_and_keeps_named_files():
    select_by_run = load_benchmark("select_by_run")
    windows = select_by_run.summarise(report()["candidates"], 0, last_step=1_520_000)
    got = [(w.run, w.first_step, w.last_step, w.policies) for w in windows]
    assert got == [
        (heldout_falls.REFERENCE, 1_740_000, 1_740_000, 1),  # named on its own: past, and kept
        ("runs/a", 1_500_000, 1_520_000, 2),  # 1,600,000 left out
        ("runs/a/policy.pt", 1_612_345, 1_612_345, 1),
    ]
    assert windows[1].falls_per_100 == pytest.approx((10.0 + 5.0) / 2)
