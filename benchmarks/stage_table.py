"""Per-stage progress of training runs from their metrics.csv (README's Hardcore table).

    python benchmarks/stage_table.py docs/runs/hardcore-*

For each run and each stage (env) it reached: policy steps, env steps, episodes and wall time
spent in that stage, the best and the last periodic evaluation (mean over its episodes, falls),
and every 100-episode test. A run is a run directory or its metrics.csv.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.metrics import METRICS_FILE, read_metrics  # noqa: E402


def _num(row: dict, key: str, fallback: str = "step") -> float:
    value = row.get(key) or row.get(fallback) or 0
    return float(value)


def stages(path: Path) -> list[dict]:
    """One summary per stage, in order."""
    rows = read_metrics(path if path.is_file() else path / METRICS_FILE)
    name = path.parent.name if path.is_file() else path.name
    out: list[dict] = []
    start = {"step": 0.0, "env_steps": 0.0, "episode": 0.0, "wall_time": 0.0}
    for stage in dict.fromkeys(r["stage"] for r in rows):
        mine = [r for r in rows if r["stage"] == stage]
        last = mine[-1]
        evals = [r for r in mine if r["kind"] == "eval"]
        best = max(evals, key=lambda r: float(r["return"])) if evals else None
        full = [r for r in mine if r["kind"] == "full_eval"]
        out.append(
            {
                "run": name,
                "stage": stage,
                "steps": _num(last, "step") - start["step"],
                "env_steps": _num(last, "env_steps") - start["env_steps"],
                "episodes": _num(last, "episode") - start["episode"],
                "minutes": (_num(last, "wall_time") - start["wall_time"]) / 60,
                "best": best,
                "last": evals[-1] if evals else None,
                "full": full,
            }
        )
        start = {k: _num(last, k) for k in start}
    return out


def _eval(row: dict | None) -> str:
    if row is None:
        return "-"
    return f"{float(row['return']):.1f} ({row['fell']} falls) at {int(float(row['step'])):,}"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("runs", nargs="+", type=Path)
    args = parser.parse_args()
    print(
        "| run | stage | policy steps | env steps | episodes | wall time (min) "
        "| best evaluation | last evaluation | 100-episode tests |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    for run in args.runs:
        for s in stages(run):
            tests = "; ".join(
                f"{float(r['return']):.1f} +- {float(r['return_std']):.1f} ({r['fell']} falls)"
                for r in s["full"]
            )
            print(
                f"| {s['run']} | {s['stage']} | {s['steps']:,.0f} | {s['env_steps']:,.0f} "
                f"| {s['episodes']:,.0f} | {s['minutes']:.1f} | {_eval(s['best'])} "
                f"| {_eval(s['last'])} | {tests or '-'} |"
            )


if __name__ == "__main__":
    main()
