"""benchmarks/same_run.py compares two runs' metrics row by row; a column that an older file
predates (``restart_from``) counts as empty, so a retrained run can be checked against a run
committed before the column existed, and a real difference is still reported."""

from .conftest import load_benchmark

same_run = load_benchmark("same_run")


def test_a_column_one_file_lacks_counts_as_empty():
    old = {"kind": "episode", "step": "71", "return": "-124.038"}
    new = {**old, "restart_from": ""}
    assert same_run.differences(old, new) == {}
    assert same_run.differences(old, {**new, "restart_from": "1200"}) == {
        "restart_from": ("", "1200")
    }


def test_a_changed_value_is_a_difference():
    a = {"kind": "episode", "step": "71", "return": "-124.038"}
    assert same_run.differences(a, {**a, "return": "-124.039"}) == {
        "return": ("-124.038", "-124.039")
    }


def test_rows_stop_at_the_step_asked_for(tmp_path):
    """``--to``: rows past the step are left out, so a quoted count does not grow with the run."""
    from bipedal_cli.metrics import METRICS_FILE

    header = "kind,env,step,episode,wall_time,return\n"
    body = "".join(f"episode,E,{s},{i},0.{i},1.5\n" for i, s in enumerate((10, 20, 30), 1))
    (tmp_path / METRICS_FILE).write_text(header + body)
    assert [r["step"] for r in same_run.rows(tmp_path, 20)] == ["10", "20"]
    assert [r["step"] for r in same_run.rows(tmp_path)] == ["10", "20", "30"]
    assert "wall_time" not in same_run.rows(tmp_path)[0]
