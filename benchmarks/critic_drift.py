"""The critics' mean value (metrics.csv's q_mean) and the training episodes, window by window:
does an actor climb its critics' errors after it starts learning?

    python benchmarks/critic_drift.py docs/runs/hardcore-warm-cvar-noanchor --from 56000 \\
        --to 64000 --every 2000

Per run and window of policy steps (an episode belongs to the window its last step falls in):
the episodes, their mean env return, the share that fell, and the mean of q_mean, the critics'
mean atom on the batch of the last update before each episode ended, and the temperature alpha
at the window's last episode.
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402


def windows(path: Path, first: int, last: int, every: int) -> list[tuple[int, int, list[dict]]]:
    rows = [
        r
        for r in read_metrics(path if path.is_file() else path / METRICS_FILE)
        if r["kind"] == "episode" and r.get("q_mean") not in (None, "")
    ]
    out = []
    for start in range(first, last, every):
        end = min(start + every, last)
        out.append((start, end, [r for r in rows if start < int(r["step"]) <= end]))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--from", dest="first", type=int, required=True)
    parser.add_argument("--to", dest="last", type=int, required=True)
    parser.add_argument("--every", type=int, required=True, help="window width in policy steps")
    args = parser.parse_args()
    print("| run | policy steps | episodes | mean return | fell | mean q_mean | last alpha |")
    print("|---|---|---|---|---|---|---|")
    for path in args.runs:
        for start, end, rows in windows(path, args.first, args.last, args.every):
            if not rows:
                print(f"| {path.name} | {start:,}-{end:,} | 0 | - | - | - | - |")
                continue
            ret = statistics.mean(float(r["return"]) for r in rows)
            fell = statistics.mean(int(float(r["fell"])) for r in rows)
            q = statistics.mean(float(r["q_mean"]) for r in rows)
            print(
                f"| {path.name} | {start:,}-{end:,} | {len(rows)} | {ret:.1f} | {fell:.0%} "
                f"| {q:.1f} | {float(rows[-1]['alpha']):.2g} |"
            )


if __name__ == "__main__":
    main()
