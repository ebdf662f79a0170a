"""Split a `bipedal eval --json` report by falls: what the episodes that fell and those that did
not scored, how many passed 300, and where the falls happened (stump, stairs, pit or flat
ground, when the report has it) (README's and docs/hardcore.md's Hardcore breakdown).

    python benchmarks/eval_breakdown.py docs/runs/hardcore-direct-seed0/eval-100.json
"""

from __future__ import annotations

import json
import sys
from collections import Counter
from statistics import mean


def main() -> None:
    for path in sys.argv[1:]:
        episodes = json.load(open(path))["episodes"]
        print(
            f"{path}: {len(episodes)} episodes, {sum(e['ret'] > 300 for e in episodes)} above 300"
        )
        for label, part in (
            ("no fall", [e["ret"] for e in episodes if not e["fell"]]),
            ("fell", [e["ret"] for e in episodes if e["fell"]]),
        ):
            if part:
                print(
                    f"  {label}: {len(part)} episodes, mean {mean(part):.1f} "
                    f"({min(part):.1f} to {max(part):.1f})"
                )
        sites = Counter(e.get("fell_at") for e in episodes if e["fell"])
        if None not in sites and sites:
            where = ", ".join(f"{kind} {n}" for kind, n in sites.most_common())
            print(f"  falls at: {where}")


if __name__ == "__main__":
    main()
