"""Training speed of runs as they ran, from their metrics.csv: policy and env steps per second
of wall time (evaluations included) between two policy steps.

    python benchmarks/run_speed.py runs/hardcore/direct-seed0 runs/hardcore/lrdecay-seed0 \\
        --from 1100000

Each run's first row at or after ``--from`` and its last row at or before ``--to`` bound the
span. README's figures for branches trained side by side come from it; the machine is whatever
the run ran on, so say which.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402


def span_speed(path: Path, first: int, last: int | None) -> dict:
    rows = read_metrics(path if path.is_file() else path / METRICS_FILE)
    inside = [
        r for r in rows if int(r["step"]) >= first and (last is None or int(r["step"]) <= last)
    ]
    if len(inside) < 2:
        raise SystemExit(f"{path}: fewer than two rows between steps {first} and {last}")
    a, b = inside[0], inside[-1]
    seconds = float(b["wall_time"]) - float(a["wall_time"])
    steps = int(b["step"]) - int(a["step"])
    env_steps = int(b["env_steps"] or b["step"]) - int(a["env_steps"] or a["step"])
    return {
        "run": path.name,
        "from": int(a["step"]),
        "to": int(b["step"]),
        "minutes": seconds / 60,
        "steps_per_s": steps / seconds,
        "env_steps_per_s": env_steps / seconds,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", type=Path)
    parser.add_argument("--from", dest="first", type=int, default=0, help="first policy step")
    parser.add_argument("--to", dest="last", type=int, default=None, help="last policy step")
    args = parser.parse_args()
    print("| run | policy steps | wall minutes | policy steps/s | env steps/s |")
    print("|---|---|---|---|---|")
    for path in args.runs:
        s = span_speed(path, args.first, args.last)
        print(
            f"| {s['run']} | {s['from']:,}-{s['to']:,} | {s['minutes']:.1f} | "
            f"{s['steps_per_s']:.1f} | {s['env_steps_per_s']:.1f} |"
        )


if __name__ == "__main__":
    main()
