"""Are two runs the same run? Compare their `metrics.csv` row by row (docs/hardcore.md,
session 10: the seed-1 run retrained on a new machine against its committed metrics).

    python benchmarks/same_run.py docs/runs/hardcore-lrdecay-seed1 runs/hardcore/lrdecay-seed1

Rows are compared on what the run decides (kind, stage, step, episode, return, length, fell and
the losses), not on wall time. It prints how many leading rows agree, up to the shorter file,
and the first that differs; the exit status is 1 when one does. ``--to STEP`` compares only the
rows up to policy step STEP, so a count quoted while a run was still training stays the same
after its metrics grow.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402

IGNORED = {"wall_time"}


def rows(run: Path, to_step: int | None = None) -> list[dict[str, str]]:
    """A run's complete rows (a row being written by a running run is left out) up to policy
    step ``to_step`` when given, wall time dropped."""
    path = run / METRICS_FILE if run.is_dir() else run
    return [
        {k: v for k, v in row.items() if k not in IGNORED}
        for row in read_metrics(path)
        if to_step is None or int(row["step"]) <= to_step
    ]


def differences(a: dict[str, str], b: dict[str, str]) -> dict[str, tuple[str, str]]:
    """The columns where two rows differ; a column one file lacks (written by an older version,
    before the column existed) counts as empty there."""
    return {
        k: (a.get(k, ""), b.get(k, "")) for k in a.keys() | b.keys() if a.get(k, "") != b.get(k, "")
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs=2, type=Path, help="two run directories or metrics files")
    parser.add_argument("--to", type=int, default=None, help="compare rows up to this policy step")
    args = parser.parse_args()
    missing = [p for p in args.runs if not p.exists()]
    if missing:
        print(f"no run directory or metrics file at {missing[0]}", file=sys.stderr)
        return 2
    a, b = (rows(p, args.to) for p in args.runs)
    n = min(len(a), len(b))
    same = next((i for i in range(n) if differences(a[i], b[i])), n)
    last = a[same - 1] if same else None
    where = f" (to step {int(last['step']):,}, episode {last['episode']})" if last else ""
    print(f"{same:,} of {n:,} rows agree{where}")
    if same < n:
        print(f"row {same + 1:,} differs: {differences(a[same], b[same])}")
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
