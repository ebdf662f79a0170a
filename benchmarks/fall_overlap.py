"""Do different policies fall on the same courses? `bipedal eval --json` reports of several
policies on the same env seeds, compared seed by seed (docs/hardcore.md, session 4).

    python benchmarks/fall_overlap.py docs/runs/hardcore-lrdecay-seed0/falls-*.json

For each pair it prints how many seeds both fell on, beside the number expected if falls were
independent of the course: a_falls * b_falls / episodes. Overlaps near that figure say the
falls belong to the policy (a stumble it makes here and not there), not to courses that are
hard for every policy; then the cure is a steadier policy, and choosing among snapshots or
averaging them cannot remove the falls. Each pair's seeds are listed, with how many returns
agree to 1e-6 (the same policy's reports from two kinds of CPU, session 33).
"""

from __future__ import annotations

import json
import sys
from itertools import combinations
from pathlib import Path


def fell_seeds(report: dict) -> set[int]:
    return {int(e["seed"]) for e in report["episodes"] if e["fell"]}


def same_returns(a: dict, b: dict) -> int:
    """Episodes whose returns agree to 1e-6: all of them for one policy on one kind of CPU; a
    policy evaluated on two kinds of CPU may share none (docs/hardcore.md, session 33)."""
    pairs = zip(a["episodes"], b["episodes"], strict=True)
    return sum(abs(x["ret"] - y["ret"]) <= 1e-6 for x, y in pairs)


def main() -> None:
    paths = [Path(p) for p in sys.argv[1:]]
    if len(paths) < 2:
        raise SystemExit("usage: fall_overlap.py REPORT.json REPORT.json [...]")
    reports = {p.stem: json.loads(p.read_text()) for p in paths}
    seeds = {name: [int(e["seed"]) for e in r["episodes"]] for name, r in reports.items()}
    first = next(iter(seeds.values()))
    if any(s != first for s in seeds.values()):
        raise SystemExit("the reports were not made on the same env seeds")
    falls = {name: fell_seeds(r) for name, r in reports.items()}
    episodes = len(first)
    for name, fell in falls.items():
        print(f"{name}: {len(fell)} falls in {episodes} episodes")
    for a, b in combinations(falls, 2):
        expected = len(falls[a]) * len(falls[b]) / episodes
        print(f"{a} & {b}: both fell on {len(falls[a] & falls[b])} (independent: {expected:.1f})")
        print(
            f"  seeds: both {sorted(falls[a] & falls[b])}, only the first "
            f"{sorted(falls[a] - falls[b])}, only the second {sorted(falls[b] - falls[a])}; "
            f"returns equal to 1e-6: {same_returns(reports[a], reports[b])} of {episodes}"
        )
    every = set().union(*falls.values())
    print(f"seeds where any of the {len(falls)} fell: {len(every)} of {episodes}")


if __name__ == "__main__":
    main()
