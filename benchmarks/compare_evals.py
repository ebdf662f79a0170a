"""Periodic evaluations of runs side by side from a policy step on (branches of one run, say).

    python benchmarks/compare_evals.py docs/runs/hardcore-direct-seed0 \\
        docs/runs/hardcore-lrdecay-seed0 --from 1100000
    python benchmarks/compare_evals.py docs/runs/hardcore-lrdecay-seed0 \\
        docs/runs/hardcore-h8-curated-seed0 --to 300000     # two runs at equal steps
    python benchmarks/compare_evals.py docs/runs/hardcore-lrdecay-cvar25-seed0 \\
        runs/hardcore/lrdecay-cvar25-ar2-seed0 --env-steps --to 3000000

With ``--env-steps`` the window and the rows count env steps instead of policy steps: runs with
different action repeats compare at equal experience.

Prints one row per evaluation step (each run's mean and falls there), then per run: how many
evaluations, their mean and median, the best, the mean falls per evaluation, every 100-episode
test, and its training episodes after ``--from`` (how many, their mean env return, how many
fell). First it says whether the runs' metrics agree before ``--from`` (a branch and its
source must). README and docs/hardcore.md take their A/B figures from it.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import COLUMNS, FRESH_KINDS, METRICS_FILE, read_metrics  # noqa: E402


def run_rows(path: Path) -> list[dict]:
    """The metrics rows of a run directory or of a metrics.csv file."""
    return read_metrics(path if path.is_file() else path / METRICS_FILE)


def evaluations(
    path: Path, first: int, kind: str = "eval", last: int | None = None, axis: str = "step"
) -> dict[int, tuple[float, int]]:
    """{position: (mean return, falls)} of the ``kind`` rows with ``first`` <= position <=
    ``last``, where position is the row's ``axis`` column: "step" (policy steps) or
    "env_steps"."""
    rows = run_rows(path)
    end = last if last is not None else 1 << 62
    return {
        int(r[axis]): (float(r["return"]), int(float(r["fell"])))
        for r in rows
        if r["kind"] == kind and first <= int(r[axis]) <= end
    }


def training_episodes(
    path: Path | list[dict], first: int, last: int | None = None, axis: str = "step"
) -> tuple[int, float, float]:
    """Fresh training episodes (probes of the deterministic policy included, restarts near
    falls not) ending after ``first`` (and at or before ``last``) on ``axis``: count, mean env
    return, fraction that fell. ``path`` may be the run's rows, already read (:func:`run_rows`)."""
    rows = run_rows(path) if isinstance(path, Path) else path
    end = last if last is not None else 1 << 62
    mine = [r for r in rows if r["kind"] in FRESH_KINDS and first < int(r[axis]) <= end]
    if not mine:
        return 0, float("nan"), float("nan")
    returns = [float(r["return"]) for r in mine]
    falls = [int(float(r["fell"])) for r in mine]
    return len(mine), statistics.mean(returns), statistics.mean(falls)


def shared_rows(paths: list[Path], before: int, axis: str = "step") -> tuple[int, bool]:
    """How many metrics rows the runs hold before ``before`` on ``axis``, and whether they are
    the same in every run (wall times aside): a branch and its source must agree there."""
    tables = [
        [
            tuple(r.get(k, "") for k in COLUMNS if k != "wall_time")  # newer columns: empty
            for r in read_metrics(p if p.is_file() else p / METRICS_FILE)
            if int(r[axis]) < before
        ]
        for p in paths
    ]
    return len(tables[0]), all(t == tables[0] for t in tables)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--from", dest="first", type=int, default=0, help="first policy step")
    parser.add_argument(
        "--to", dest="last", type=int, help="last policy step (runs of unequal length)"
    )
    parser.add_argument(
        "--env-steps",
        action="store_true",
        help="--from, --to and the rows count env steps (runs of different action repeats)",
    )
    args = parser.parse_args()
    axis, unit = ("env_steps", "env step") if args.env_steps else ("step", "policy step")
    names = [p.name for p in args.runs]
    evals = [evaluations(p, args.first, last=args.last, axis=axis) for p in args.runs]
    print(f"| {unit} | " + " | ".join(names) + " |")
    print("|---|" + "---|" * len(names))
    for step in sorted(set().union(*evals)):
        cells = [f"{e[step][0]:.1f} ({e[step][1]} falls)" if step in e else "-" for e in evals]
        print(f"| {step:,} | " + " | ".join(cells) + " |")
    count, same = shared_rows(args.runs, args.first, axis)
    print(f"\nrows before {unit} {args.first:,}: {count:,} in the first run, ", end="")
    print("the same in every run" if same else "NOT the same in every run")
    print()
    print(
        "| run | evaluations | mean | median | best | falls per evaluation | 100-episode tests "
        "| training episodes: count, mean return, fell |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for path, name, e in zip(args.runs, names, evals, strict=True):
        count, mean_return, fell = training_episodes(path, args.first, args.last, axis)
        if not e:  # no evaluation in the window: its training episodes still tell
            episodes = f"{count:,}, {mean_return:.1f}, {fell:.0%}" if count else "-"
            print(f"| {name} | 0 | - | - | - | - | - | {episodes} |")
            continue
        means = [m for m, _ in e.values()]
        best = max(e, key=lambda s: e[s][0])
        tests = evaluations(path, args.first, "full_eval", args.last, axis)
        test_text = ", ".join(f"{m:.1f} ({f} falls) at {s:,}" for s, (m, f) in tests.items())
        print(
            f"| {name} | {len(e)} | {statistics.mean(means):.1f} | "
            f"{statistics.median(means):.1f} | {e[best][0]:.1f} at {best:,} | "
            f"{statistics.mean(f for _, f in e.values()):.1f} | {test_text or '-'} | "
            f"{count:,}, {mean_return:.1f}, {fell:.0%} |"
        )


if __name__ == "__main__":
    main()
