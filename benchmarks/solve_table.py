"""Steps, episodes and wall time to solve, from run directories' metrics.csv (README's table).

    python benchmarks/solve_table.py runs/solve-seed0 runs/solve-seed1 runs/solve-seed2
    python benchmarks/solve_table.py docs/runs/*/metrics.csv      # the committed copies

A run counts as solved at its first ``full_eval`` row (the 100-episode deterministic test that
``--until-solved`` runs) whose mean is above 300. A run without one is reported with the steps it
reached and its best evaluations.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402


def summarize_run(run_dir: Path, threshold: float = 300.0) -> dict:
    path = run_dir if run_dir.is_file() else run_dir / METRICS_FILE  # a run dir or its csv
    rows = read_metrics(path)
    seed = run_dir.parent.name if run_dir.is_file() else run_dir.name
    full = [r for r in rows if r["kind"] == "full_eval"]
    solved = next((r for r in full if float(r["return"]) > threshold), None)
    last = rows[-1]
    evals = [r for r in rows if r["kind"] == "eval"]
    best = max(evals, key=lambda r: float(r["return"])) if evals else None
    return {
        "run": seed,
        "solved": solved is not None,
        "steps": int(float((solved or last)["step"])),
        "episodes": int(float((solved or last)["episode"])),
        "minutes": float((solved or last)["wall_time"]) / 60,
        "full_eval": (
            f"{float(solved['return']):.1f} +- {float(solved['return_std']):.1f}, "
            f"{solved['fell']} falls"
            if solved
            else "; ".join(f"{float(r['return']):.1f} at {int(float(r['step'])):,}" for r in full)
            or "-"
        ),
        "best_eval": f"{float(best['return']):.1f} at {int(float(best['step'])):,}"
        if best
        else "-",
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", type=Path)
    args = parser.parse_args()
    results = [summarize_run(r) for r in args.runs]
    print(
        "| run | solved | env steps | episodes | wall time (min) | 100-episode evaluation "
        "| best 5-episode evaluation |"
    )
    print("|---|---|---|---|---|---|---|")
    for r in results:
        steps = f"{r['steps']:,}" if r["solved"] else f"not by {r['steps']:,}"
        print(
            f"| {r['run']} | {'yes' if r['solved'] else 'no'} | {steps} | {r['episodes']} | "
            f"{r['minutes']:.1f} | {r['full_eval']} | {r['best_eval']} |"
        )
    solved = [r for r in results if r["solved"]]
    print(f"solved {len(solved)} of {len(results)}")
    for key, label in (("steps", "env steps"), ("episodes", "episodes"), ("minutes", "min")):
        print(f"{label} to solve, median over all runs: {censored_median(results, key)}", end="")
        if solved:
            values = [r[key] for r in solved]
            print(f"; range of the solved runs {min(values):,.1f}-{max(values):,.1f}", end="")
        print()


def censored_median(results: list[dict], key: str) -> str:
    """The median over every run, a run that did not solve counting as "more than it reached".

    Leaving unsolved runs out would flatter the median; when the middle of the sorted runs is an
    unsolved one, the median is only known to exceed what that run reached: "> X".
    """
    ordered = sorted(results, key=lambda r: (not r["solved"], r[key]))  # unsolved runs last
    n = len(ordered)
    middle = ordered[(n - 1) // 2 : n // 2 + 1]  # one run (n odd) or two (n even)
    if all(r["solved"] for r in middle):
        return f"{statistics.mean(r[key] for r in middle):,.1f}"
    # the unsolved value is a lower bound, so the mean of the middle pair is one too
    return f"> {statistics.mean(r[key] for r in middle):,.1f}"


if __name__ == "__main__":
    main()
