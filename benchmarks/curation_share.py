"""How much of a run's experience FORK's replay curation lets into the replay buffer, per span
of policy steps, from the run's metrics.csv (docs/hardcore.md).

    python benchmarks/curation_share.py docs/runs/hardcore-h8-curated-seed0
    python benchmarks/curation_share.py docs/runs/hardcore-lrdecay-seed0 --threshold 250

An episode is stored when it fell or its env return is below the threshold (the run's own
``train.replay_keep_below`` from its config.yaml, or ``--threshold`` for a run without curation:
what curation would have kept). Its policy steps are the step count it added, the difference
between its row's step and the previous episode's.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.episodes import curation_keeps  # noqa: E402
from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402


def stored_share(rows: list[dict], threshold: float, start: int, every: int) -> list[tuple]:
    """Per span [k * every, (k + 1) * every): episodes, the share of them stored, the share of
    policy steps stored. Episodes that started before ``start`` all count as stored."""
    spans: dict[int, list[int]] = {}
    previous = 0
    for r in (r for r in rows if r["kind"] == "episode"):
        step = int(r["step"])
        steps = step - previous
        fell = bool(int(float(r["fell"])))
        stored = previous < start or curation_keeps(fell, float(r["return"]), threshold)
        span = spans.setdefault(step // every, [0, 0, 0, 0])
        span[0] += 1
        span[1] += stored
        span[2] += steps
        span[3] += steps * stored
        previous = step
    return [
        (k * every, (k + 1) * every, n, kept / n, steps_kept / max(steps, 1))
        for k, (n, kept, steps, steps_kept) in sorted(spans.items())
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("run", type=Path)
    parser.add_argument("--threshold", type=float, help="default: the run's replay_keep_below")
    parser.add_argument("--every", type=int, default=100_000, help="policy steps per span")
    args = parser.parse_args()
    train_cfg = yaml.safe_load((args.run / "config.yaml").read_text())["train"]
    threshold = args.threshold
    if threshold is None:
        threshold = train_cfg.get("replay_keep_below")
        if threshold is None:
            raise SystemExit(f"{args.run}: no replay curation in its config; pass --threshold")
    start = int(train_cfg.get("replay_curation_start") or 0) if args.threshold is None else 0
    rows = read_metrics(args.run / METRICS_FILE)
    print(f"{args.run}: episodes that fell or scored below {threshold:g}")
    print("| policy steps | episodes | episodes stored | policy steps stored |")
    print("|---|---|---|---|")
    for first, last, n, episodes, steps in stored_share(rows, threshold, start, args.every):
        print(f"| {first:,}-{last:,} | {n:,} | {episodes:.0%} | {steps:.0%} |")


if __name__ == "__main__":
    main()
