"""Pool every held-out block a policy has played into one estimate with a confidence interval
(docs/hardcore.md, session 7): its mean return over all those episodes, and its fall rate.

    python benchmarks/pool_heldout.py docs/runs/hardcore-select-session[4-9]*.json \\
        docs/runs/hardcore-confirm-session4.json docs/runs/hardcore-average-screen-session4.json

Inputs are `bipedal select --json` reports (their first round and their confirmation round are
separate blocks of env seeds). A policy is the sha256 of its file, which reports record since
session 7. An older report's row (no sha256) is matched by its path (made relative to the
working directory) and policy step to the one file that newer reports saw there, and stays a
row of its own when they saw two (a new policy shipped under the same name and step). A block
of seeds is counted once per policy. Leave out the report that chose a policy: its block is
biased in the policy's favour.

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


def place(candidate: dict) -> tuple[str, int]:
    """(path relative to the working directory, policy step) of a report's row."""
    p = Path(candidate["path"])
    if p.is_absolute():
        try:
            p = p.relative_to(Path.cwd())
        except ValueError:
            pass
    return str(p), int(candidate["step"])


def rounds(report: dict) -> list[tuple[tuple[int, int], list[dict]]]:
    """The report's blocks: ((first seed, last seed), candidates) for each round."""
    out = [(tuple(report["seeds"]), report["candidates"])]
    if report.get("confirm"):
        out.append((tuple(report["confirm"]["seeds"]), report["confirm"]["finalists"]))
    return out


def collect(reports: list[dict]) -> dict[str, dict]:
    """policy id -> {"place": (path, step), "blocks": {seed block -> held-out summary}}; a
    block seen twice is kept once."""
    rows = [(seeds, c) for report in reports for seeds, cs in rounds(report) for c in cs]
    files_at: dict[tuple[str, int], set[str]] = defaultdict(set)
    for _, c in rows:
        if c.get("sha256"):
            files_at[place(c)].add(c["sha256"])
    policies: dict[str, dict] = {}
    for seeds, c in rows:
        where = place(c)
        known = files_at.get(where, set())
        if c.get("sha256"):
            key = c["sha256"]
        elif len(known) == 1:
            key = next(iter(known))
        else:  # never recorded, or two files under one name and step: its own row
            key = f"{where[0]}@{where[1]}" + (" (ambiguous)" if known else "")
        entry = policies.setdefault(key, {"place": where, "blocks": {}})
        entry["blocks"].setdefault(seeds, c["held_out"])
    return policies


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
    for key, entry in sorted(policies.items(), key=lambda kv: -len(kv[1]["blocks"])):
        (path, step), blocks = entry["place"], entry["blocks"]
        if len(blocks) < args.min_blocks:
            continue
        if key.endswith("(ambiguous)"):
            path += " (rows without sha256: two files were seen here)"
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
