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
