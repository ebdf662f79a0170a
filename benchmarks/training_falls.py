"""How often runs' training episodes fell, window by window of policy steps, side by side.

    python benchmarks/training_falls.py docs/runs/hardcore-lrdecay-cvar25-seed0 \\
        docs/runs/hardcore-lrdecay-cvar25-control-seed0 --from 1050000 --to 1700000 --every 50000

One row per run, one column per window (A, A + every], (A + every, A + 2 every], ...: the share
of the fresh training episodes that ended in the window and fell (probes of the deterministic
policy count, restarts near falls do not: ``compare_evals.training_episodes``), with how many
ended there. A window a run did not reach reads "-". The stochastic training policy's falls
show where a change of recipe, a restart's refill or a move begins to tell, long before enough
held-out episodes say so.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from compare_evals import run_rows, training_episodes  # noqa: E402

from bipedal_cli.metrics import METRICS_FILE  # noqa: E402


def windows(first: int, last: int, every: int) -> list[tuple[int, int]]:
    """(A, B] windows of ``every`` policy steps from ``first`` up to ``last`` (the last one may be
    shorter)."""
    if every <= 0 or last <= first:
        raise ValueError("--every must be positive and --to above --from")
    return [(a, min(a + every, last)) for a in range(first, last, every)]


def fall_shares(path: Path, spans: list[tuple[int, int]]) -> list[tuple[int, float]]:
    """(episodes, share that fell) of the run at ``path`` in each (A, B] span (its metrics
    read once)."""
    rows = run_rows(path)
    out = []
    for a, b in spans:
        count, _, fell = training_episodes(rows, a, b)  # count, mean return, share that fell
        out.append((count, fell))
    return out


def cell(count: int, fell: float) -> str:
    return "-" if count == 0 else f"{100 * fell:.0f}% of {count}"


def table(runs: list[Path], spans: list[tuple[int, int]]) -> str:
    head = ["run"] + [f"{a + 1:,}-{b:,}" for a, b in spans]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for run in runs:
        cells = [cell(c, f) for c, f in fall_shares(run, spans)]
        lines.append("| " + " | ".join([run.name, *cells]) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", nargs="+", type=Path, help="run directories or metrics.csv files")
    ap.add_argument("--from", dest="first", type=int, required=True, help="policy step A")
    ap.add_argument("--to", dest="last", type=int, required=True, help="the last window's end")
    ap.add_argument("--every", type=int, default=50_000, help="window length in policy steps")
    args = ap.parse_args(argv)
    try:
        spans = windows(args.first, args.last, args.every)
    except ValueError as e:
        ap.error(str(e))
    for run in args.runs:
        if not (run if run.is_file() else run / METRICS_FILE).exists():
            ap.error(f"{run}: no {METRICS_FILE} there (expected a run directory or the file)")
    print(table(args.runs, spans))


if __name__ == "__main__":
    main()
