"""Summarise a `bipedal select --json` report by run: over each run's candidates (all played the
same held-out seeds), the mean held-out return, the falls per 100 episodes, the median return and
the mean episode length, optionally in windows of policy steps (docs/hardcore.md, session 6).

    python benchmarks/select_by_run.py docs/runs/hardcore-select-session6.json --every 100000

A run is the directory that holds `policies/`; a policy file named on its own is its own row.
Comparing runs this way weighs every kept policy, not the one a selection happens to pick.
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path
from statistics import mean


def run_of(path: str) -> str:
    p = Path(path)
    return str(p.parent.parent) if p.parent.name == "policies" else str(p)


def summarise(candidates: list[dict], every: int) -> list[tuple]:
    """(run, first step, last step, policies, mean return, falls per 100, median, length)."""
    groups: dict[tuple[str, int], list[dict]] = defaultdict(list)
    for c in candidates:
        window = c["step"] // every * every if every else 0
        groups[(run_of(c["path"]), window)].append(c)
    rows = []
    for (run, _), group in sorted(groups.items()):
        held = [c["held_out"] for c in group]
        rows.append(
            (
                run,
                min(c["step"] for c in group),
                max(c["step"] for c in group),
                len(group),
                mean(h["mean"] for h in held),
                mean(100 * h["falls"] / h["episodes"] for h in held),
                mean(h["median"] for h in held),
                mean(h["mean_length"] for h in held),
            )
        )
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("report", type=Path, help="a `bipedal select --json` file")
    parser.add_argument("--every", type=int, default=0, help="window of policy steps (0: none)")
    args = parser.parse_args()
    report = json.loads(args.report.read_text())
    first, last = report["seeds"]
    print(f"{args.report}: held-out seeds {first:,}-{last:,}")
    print(
        "| run | policy steps | policies | mean return | falls per 100 | median | mean length |\n"
        "|---|---|---|---|---|---|---|"
    )
    for run, lo, hi, n, ret, falls, median, length in summarise(report["candidates"], args.every):
        steps = f"{lo:,}" if lo == hi else f"{lo:,}-{hi:,}"
        print(f"| {run} | {steps} | {n} | {ret:.1f} | {falls:.1f} | {median:.1f} | {length:.0f} |")


if __name__ == "__main__":
    main()
