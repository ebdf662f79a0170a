import numpy as np

from bipedal_cli.metrics import MetricsWriter, read_metrics


def test_rows_are_written_as_plain_numbers_and_truncated_on_resume(tmp_path):
    writer = MetricsWriter(tmp_path / "metrics.csv")
    writer.write({"kind": "episode", "step": 10, "fell": np.bool_(True), "return": np.float64(1.5)})
    writer.write({"kind": "episode", "step": 20, "fell": False, "return": float("nan")})
    writer.write({"kind": "eval", "step": 30, "return": 3.0})
    rows = read_metrics(tmp_path / "metrics.csv")
    assert [(r["fell"], r["return"]) for r in rows] == [("1", "1.5"), ("0", ""), ("", "3")]
    writer.truncate_after(20)
    assert [r["step"] for r in read_metrics(tmp_path / "metrics.csv")] == ["10", "20"]
