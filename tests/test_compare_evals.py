"""benchmarks/compare_evals.py windows runs by policy steps, or by env steps for runs whose
action repeats differ."""

import csv

from bipedal_cli.metrics import COLUMNS

from .conftest import load_benchmark

compare_evals = load_benchmark("compare_evals")


def write_run(path, repeat, evals, episodes):
    """A metrics.csv with evaluations {policy step: (mean, falls)} and training episodes
    {policy step: (return, fell)} of a run at action repeat ``repeat``."""
    rows = [("eval", s, m, f) for s, (m, f) in evals.items()]
    rows += [("episode", s, r, f) for s, (r, f) in episodes.items()]
    with path.open("w", newline="") as f:
        writer = csv.DictWriter(f, COLUMNS, restval="")
        writer.writeheader()
        for kind, step, value, fell in sorted(rows, key=lambda r: r[1]):
            writer.writerow(
                {"kind": kind, "stage": "h", "step": step, "episode": 0, "wall_time": 0,
                 "return": value, "fell": fell, "env_steps": step * repeat}
            )  # fmt: skip
    return path


def test_env_steps_window_runs_of_different_action_repeats_at_equal_experience(tmp_path):
    repeat3 = write_run(tmp_path / "r3.csv", 3, {100: (10.0, 5), 200: (20.0, 4)}, {150: (1.0, 1)})
    repeat2 = write_run(
        tmp_path / "r2.csv", 2, {150: (30.0, 3), 300: (40.0, 2)}, {200: (5.0, 0), 301: (7.0, 1)}
    )
    # env steps 301-600: repeat 3's evaluation at 200 (600) and repeat 2's at 300 (600)
    assert compare_evals.evaluations(repeat3, 301, last=600, axis="env_steps") == {600: (20.0, 4)}
    assert compare_evals.evaluations(repeat2, 301, last=600, axis="env_steps") == {600: (40.0, 2)}
    # by policy steps the same window holds neither
    assert compare_evals.evaluations(repeat3, 301, last=600) == {}
    # training episodes ending in env steps 301-600: repeat 2's at 200 (400), not at 301 (602)
    assert compare_evals.training_episodes(repeat2, 300, 600, axis="env_steps") == (1, 5.0, 0.0)
    assert compare_evals.training_episodes(repeat2, 150, 301) == (2, 6.0, 0.5)
