"""Pool every held-out block a policy has played into one estimate with a confidence interval
(docs/hardcore.md, session 7): its mean return over all those episodes, and its fall rate.

    python benchmarks/pool_heldout.py docs/runs/hardcore-select-session[4-9]*.json \\
        docs/runs/hardcore-confirm-session4.json docs/runs/hardcore-average-screen-session4.json

Inputs are `bipedal select --json` reports (their first round and their confirmation round are
separate blocks of env seeds). A policy is its path as the report names it (made relative to
the working directory) and its policy step. A block of seeds is counted once per policy. Leave
out the report that chose a policy: its block is biased in the policy's favour.

Block i has n_i episodes, mean m_i and population standard deviation s_i (`bipedal eval`'s). Over
N = sum n_i episodes:

    M = (1 / N) sum_i n_i m_i
    S^2 = (1 / N) sum_i n_i (s_i^2 + (m_i - M)^2)          (the population variance of all)
    95% interval for the mean: M +- 1.96 S / sqrt(N - 1)   (bipedal_cli.evaluation.mean_interval)

and for F falls in N episodes the Wilson score interval, z = 1.96, p = F / N:

    (p + z^2 / 2N +- z sqrt(p (1 - p) / N + z^2 / 4N^2)) / (1 + z^2 / N)
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections import defaultdict
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from bipedal_cli.evaluation import mean_interval  # noqa: E402

Z95 = 1.96


def pool_blocks(blocks: list[tuple[int, float, float]]) -> tuple[int, float, float]:
    """(N, M, S) of the union of blocks given as (n_i, m_i, s_i), s_i a population std."""
    total = sum(n for n, _, _ in blocks)
    mean = sum(n * m for n, m, _ in blocks) / total
    var = sum(n * (s * s + (m - mean) ** 2) for n, m, s in blocks) / total
    return total, mean, math.sqrt(var)


def wilson_interval(falls: int, total: int, z: float = Z95) -> tuple[float, float]:
    """The Wilson score interval of a proportion falls / total."""
    p = falls / total
    centre = p + z * z / (2 * total)
    half = z * math.sqrt(p * (1 - p) / total + z * z / (4 * total * total))
    scale = 1 + z * z / total
    return (centre - half) / scale, (centre + half) / scale


def policy_key(path: str, step: int) -> tuple[str, int]:
    p = Path(path)
    if p.is_absolute():
        try:
            p = p.relative_to(Path.cwd())
        except ValueError:
            pass
    return str(p), int(step)


def rounds(report: dict) -> list[tuple[tuple[int, int], list[dict]]]:
    """The report's blocks: ((first seed, last seed), candidates) for each round."""
    out = [(tuple(report["seeds"]), report["candidates"])]
    if report.get("confirm"):
        out.append((tuple(report["confirm"]["seeds"]), report["confirm"]["finalists"]))
    return out


def collect(reports: list[dict]) -> dict[tuple[str, int], dict[tuple[int, int], dict]]:
    """policy -> {seed block -> its held-out summary}; a block seen twice is kept once."""
    seen: dict[tuple[str, int], dict[tuple[int, int], dict]] = defaultdict(dict)
    for report in reports:
        for seeds, candidates in rounds(report):
            for c in candidates:
                seen[policy_key(c["path"], c["step"])].setdefault(seeds, c["held_out"])
    return seen


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("reports", type=Path, nargs="+", help="`bipedal select --json` files")
    parser.add_argument("--min-blocks", type=int, default=2, help="policies seen in this many")
    args = parser.parse_args()
    policies = collect([json.loads(p.read_text()) for p in args.reports])
    print(
        "| policy | step | blocks | episodes | mean return (95% interval) "
        "| falls per 100 (95% interval) |\n|---|---|---|---|---|---|"
    )
    for (path, step), blocks in sorted(policies.items(), key=lambda kv: -len(kv[1])):
        if len(blocks) < args.min_blocks:
            continue
        held = list(blocks.values())
        total, mean, std = pool_blocks([(h["episodes"], h["mean"], h["std"]) for h in held])
        lo, hi = mean_interval(total, mean, std)
        falls = sum(h["falls"] for h in held)
        f_lo, f_hi = wilson_interval(falls, total)
        print(
            f"| {path} | {step:,} | {len(blocks)} | {total:,} | {mean:.1f} ({lo:.1f}-{hi:.1f}) "
            f"| {100 * falls / total:.1f} ({100 * f_lo:.1f}-{100 * f_hi:.1f}) |"
        )


if __name__ == "__main__":
    main()
