"""benchmarks/training_falls.py: the share of training episodes that fell, window by window."""

import pytest

from .conftest import load_benchmark
from .test_compare_evals import write_run

training_falls = load_benchmark("training_falls")


def test_windows_are_half_open_and_the_last_may_be_short():
    assert training_falls.windows(100, 350, 100) == [(100, 200), (200, 300), (300, 350)]
    with pytest.raises(ValueError):
        training_falls.windows(100, 100, 50)
    with pytest.raises(ValueError):
        training_falls.windows(0, 100, 0)


def test_each_episode_counts_in_the_window_it_ended_in(tmp_path):
    episodes = {110: (1.0, 1), 200: (2.0, 0), 201: (3.0, 1), 250: (4.0, 1), 300: (5.0, 0)}
    run = write_run(tmp_path / "run.csv", 1, {}, episodes)
    spans = training_falls.windows(100, 400, 100)
    shares = training_falls.fall_shares(run, spans)
    assert shares[0] == (2, 0.5)  # 110 fell, 200 did not: (100, 200]
    assert shares[1][0] == 3 and shares[1][1] == pytest.approx(2 / 3)  # 201, 250 fell; 300 not
    assert shares[2][0] == 0  # nothing ended in (300, 400]
    table = training_falls.table([run], spans)
    assert "| run.csv | 50% of 2 | 67% of 3 | - |" in table
    assert "101-200" in table.splitlines()[0]


def test_a_missing_run_is_a_one_line_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        training_falls.main([str(tmp_path / "nowhere"), "--from", "0", "--to", "10"])
    assert exit_info.value.code != 0
    assert "no metrics.csv there" in capsys.readouterr().err
