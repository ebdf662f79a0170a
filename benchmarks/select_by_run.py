"""Summarise `bipedal select --json` reports by run: over each run's candidates (all played the
same held-out seeds), the mean held-out return, the falls per 100 episodes, where they fell (all
the group's falls, by obstacle), the median return and the mean episode length, optionally in
windows of policy steps (docs/hardcore.md, session 6). One table per report.

    python benchmarks/select_by_run.py docs/runs/hardcore-select-session6.json --every 100000

`--to STEP` leaves out kept policies past STEP, so that runs stopped at different steps are
summarised over the same span; a policy file named on its own (the shipped one, a run's last
`policy.pt`) always stays.

A run is the directory that holds `policies/`; a policy file named on its own is its own row.
Comparing runs this way weighs every kept policy, not the one a selection happens to pick.
"""

from __future__ import annotations

import argparse
import json
from collections import Counter, defaultdict
from pathlib import Path
from statistics import mean
from typing import NamedTuple


def run_of(path: str) -> str:
    p = Path(path)
    return str(p.parent.parent) if p.parent.name == "policies" else str(p)


def group_of(candidate: dict, every: int) -> tuple[str, int]:
    """(run, first step of its window of `every` policy steps; 0 for no windows)."""
    window = candidate["step"] // every * every if every else 0
    return run_of(candidate["path"]), window


class WindowSummary(NamedTuple):
    """One run's candidates in one window of policy steps, summarised."""

    run: str
    first_step: int
    last_step: int
    policies: int
    mean_return: float
    falls_per_100: float
    falls_at: Counter  # all the window's falls, by obstacle, as `select` records them
    median: float
    mean_length: float


def kept_past(candidate: dict, last_step: int | None) -> bool:
    """Whether ``candidate`` is a kept policy (``RUN/policies/step-N.pt``) past ``last_step``."""
    kept = Path(candidate["path"]).parent.name == "policies"
    return last_step is not None and kept and candidate["step"] > last_step


def summarise(
    candidates: list[dict], every: int, last_step: int | None = None
) -> list[WindowSummary]:
    """One WindowSummary per (run, window of `every` policy steps), in run then step order,
    leaving out kept policies past ``last_step`` (None: none left out)."""
    groups: dict[tuple[str, int], list[dict]] = defaultdict(list)
    for c in candidates:
        if not kept_past(c, last_step):
            groups[group_of(c, every)].append(c)
    rows = []
    for (run, _), group in sorted(groups.items()):
        held = [c["held_out"] for c in group]
        falls_at: Counter = Counter()
        for h in held:
            falls_at.update(h.get("falls_at") or {})
        rows.append(
            WindowSummary(
                run=run,
                first_step=min(c["step"] for c in group),
                last_step=max(c["step"] for c in group),
                policies=len(group),
                mean_return=mean(h["mean"] for h in held),
                falls_per_100=mean(100 * h["falls"] / h["episodes"] for h in held),
                falls_at=falls_at,
                median=mean(h["median"] for h in held),
                mean_length=mean(h["mean_length"] for h in held),
            )
        )
    return rows


def print_report(path: Path, every: int, last_step: int | None = None) -> None:
    report = json.loads(path.read_text())
    first, last = report["seeds"]
    print(f"{path}: held-out seeds {first:,}-{last:,}")
    print(
        "| run | policy steps | policies | mean return | falls per 100 | where they fell "
        "| median | mean length |\n|---|---|---|---|---|---|---|---|"
    )
    for w in summarise(report["candidates"], every, last_step):
        steps = f"{w.first_step:,}"
        if w.last_step != w.first_step:
            steps += f"-{w.last_step:,}"
        at = ", ".join(f"{k} {v}" for k, v in w.falls_at.most_common()) or "-"
        print(
            f"| {w.run} | {steps} | {w.policies} | {w.mean_return:.1f} | {w.falls_per_100:.1f} "
            f"| {at} | {w.median:.1f} | {w.mean_length:.0f} |"
        )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("reports", type=Path, nargs="+", help="`bipedal select --json` files")
    parser.add_argument("--every", type=int, default=0, help="window of policy steps (0: none)")
    parser.add_argument(
        "--to", type=int, default=None, help="leave out kept policies past this policy step"
    )
    args = parser.parse_args()
    for path in args.reports:
        print_report(path, args.every, args.to)


if __name__ == "__main__":
    main()
