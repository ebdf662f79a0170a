"""The run's metrics file: one CSV, a row per finished episode and per evaluation."""

from __future__ import annotations

import csv
import io
import math
import os
import zlib
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from .errors import UserError
from .paths import atomic_path

COLUMNS = [
    "kind",  # episode | restart (train.fall_restart: begun near a fall) | probe (a fresh episode
    # of the deterministic policy: train.fall_restart_probe) | eval | full_eval
    "stage",  # env id the row was produced on
    "step",  # policy steps so far (transitions stored)
    "episode",  # finished training episodes so far
    "wall_time",  # seconds of training, summed over resumes
    "return",  # episode return, or the mean return of an evaluation
    "return_std",  # evaluation only
    "length",  # episode length in env steps, or the mean over an evaluation
    "fell",  # episode ended on the fall penalty (or number of evaluation falls)
    "alpha",
    "critic_loss",
    "actor_loss",
    "entropy",
    "q_mean",
    "shaped_return",  # training episodes: the return the learner saw (train.fall_penalty and
    # train.reward_scale); "return" is always the env's own reward
    "env_steps",  # env steps so far ("step" counts policy steps; they differ with action repeat)
    "restart_from",  # restart rows: the env steps replayed before the learner took over
]
KINDS = ("episode", "restart", "probe", "eval", "full_eval")
FRESH_KINDS = ("episode", "probe")  # training episodes begun afresh on a new seed
METRICS_FILE = "metrics.csv"


class MetricsWriter:
    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if self.path.is_symlink():
            raise UserError(
                f"{self.path}: is a symbolic link; a run's metrics must be a regular file "
                "(bipedal never writes through a link)"
            )
        if not self.path.exists():
            with self.path.open("w", newline="") as f:
                csv.writer(f).writerow(COLUMNS)
            return
        with self.path.open(newline="") as f:
            header = next(csv.reader(f), [])
        if header != COLUMNS:  # written by an earlier version: add the new columns, empty
            self.replace_rows(read_metrics(self.path))

    def write(self, row: dict[str, Any]) -> None:
        unknown = set(row) - set(COLUMNS)
        if unknown:
            raise KeyError(f"unknown metric columns {sorted(unknown)}")
        line = io.StringIO()
        csv.writer(line).writerow([_fmt(row.get(c, "")) for c in COLUMNS])
        try:  # O_NOFOLLOW: never through a link
            fd = os.open(self.path, os.O_WRONLY | os.O_APPEND | os.O_NOFOLLOW)
            with os.fdopen(fd, "w", newline="") as f:
                f.write(line.getvalue())
        except OSError as exc:
            raise UserError(f"{self.path}: could not be written ({exc.strerror})") from None

    def truncate_after(self, step: int) -> None:
        """Drop rows logged after ``step`` (written after the checkpoint a resume starts from)."""
        rows = read_metrics(self.path)
        self.replace_rows([r for r in rows if int(float(r["step"])) <= step])

    def replace_rows(self, rows: list[dict[str, str]]) -> None:
        """The file holds ``rows`` alone, renamed into place whole."""
        with atomic_path(self.path) as tmp, tmp.open("w", newline="") as f:
            w = csv.DictWriter(f, COLUMNS, restval="")
            w.writeheader()
            w.writerows(rows)


def _fmt(value: Any) -> Any:
    if isinstance(value, (bool, np.bool_)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return "" if math.isnan(value) else f"{float(value):.6g}"
    return value


def read_metrics(path: str | Path) -> list[dict[str, str]]:
    """The rows of a metrics file; a torn row (a full disk or a power loss mid-write: too few
    fields or an unreadable step) is dropped."""
    with Path(path).open(newline="", errors="replace") as f:
        return [r for r in csv.DictReader(f) if _complete(r)]


def parse_metrics(text: str) -> list[dict[str, str]]:
    """:func:`read_metrics` of a metrics file's text (the copy a ``restart.pt`` holds)."""
    return [r for r in csv.DictReader(io.StringIO(text, newline="")) if _complete(r)]


def pack_metrics(text: str) -> bytes:
    """A metrics file's text as a restart file holds it: zlib of its UTF-8 (a third of its size)."""
    return zlib.compress(text.encode("utf-8"), 9)


def restart_metrics_text(restart: Mapping[str, Any]) -> str:
    """The metrics text of a restart file's ``restart`` entry: ``metrics_csv_zlib``
    (:func:`pack_metrics`, since 2026-12-05) or, in older files, ``metrics_csv``. Raises
    ``zlib.error`` or ``UnicodeDecodeError`` on bytes that are not a packed text."""
    if "metrics_csv_zlib" in restart:
        return zlib.decompress(restart["metrics_csv_zlib"]).decode("utf-8")
    return restart["metrics_csv"]


def _complete(row: dict) -> bool:
    if None in row or any(v is None for v in row.values()):  # too many or too few fields
        return False
    try:
        return math.isfinite(float(row["step"])) and row["kind"] in KINDS
    except (KeyError, ValueError):
        return False
