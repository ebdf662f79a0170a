"""How a run's restarts near falls (``train.fall_restart``) went, per span of policy steps, from
its metrics.csv (docs/hardcore.md, session 22).

    python benchmarks/restart_share.py docs/runs/hardcore-lrdecay-cvar25-g99-restarts-seed0 \\
        --from 1944374 --every 50000

Per span: fresh episodes (count, share that fell), restarted episodes (count, share that fell
again before their horizon, mean env steps replayed) and the share of the span's policy steps
that restarts played; probes of the deterministic policy (``train.fall_restart_probe``) count as
fresh episodes. An episode's policy steps are its row's step less the previous training
episode's (fresh or restarted).
"""

from __future__ import annotations

import argparse
import statistics
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402


def restart_spans(rows: list[dict], first: int, every: int) -> list[dict]:
    """One dict per span [first + k * every, first + (k + 1) * every) of episode end steps."""
    spans: dict[int, dict] = {}
    previous = None
    for r in rows:
        if r["kind"] not in ("episode", "probe", "restart"):
            continue
        step = int(float(r["step"]))
        played = step - previous if previous is not None else 0
        previous = step
        if step < first:
            continue
        span = spans.setdefault(
            (step - first) // every,
            {"fresh": [], "restart": [], "replayed": [], "steps": 0, "restart_steps": 0},
        )
        fell = int(float(r["fell"]))
        span["steps"] += played
        if r["kind"] == "restart":
            span["restart"].append(fell)
            span["replayed"].append(int(float(r["restart_from"])))
            span["restart_steps"] += played
        else:
            span["fresh"].append(fell)
    return [
        {
            "from": first + k * every,
            "fresh": len(s["fresh"]),
            "fresh_fell": statistics.mean(s["fresh"]) if s["fresh"] else float("nan"),
            "restarts": len(s["restart"]),
            "restart_fell": statistics.mean(s["restart"]) if s["restart"] else float("nan"),
            "replayed": statistics.mean(s["replayed"]) if s["replayed"] else float("nan"),
            "restart_share": s["restart_steps"] / s["steps"] if s["steps"] else float("nan"),
        }
        for k, s in sorted(spans.items())
    ]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("run", type=Path, help="a run directory or its metrics.csv")
    parser.add_argument("--from", dest="first", type=int, default=0, help="first policy step")
    parser.add_argument("--every", type=int, default=50_000, help="policy steps per span")
    args = parser.parse_args()
    path = args.run if args.run.is_file() else args.run / METRICS_FILE
    print(
        "| policy steps | fresh episodes | fresh that fell | restarts | restarts that fell "
        "| env steps replayed (mean) | policy steps from restarts |"
    )
    print("|---|---|---|---|---|---|---|")
    for s in restart_spans(read_metrics(path), args.first, args.every):
        print(
            f"| {s['from']:,}-{s['from'] + args.every - 1:,} | {s['fresh']} | "
            f"{s['fresh_fell']:.0%} | {s['restarts']} | {s['restart_fell']:.0%} | "
            f"{s['replayed']:.0f} | {s['restart_share']:.0%} |"
        )


if __name__ == "__main__":
    main()
