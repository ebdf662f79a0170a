"""Intervals on scores: `bipedal eval`'s verdict gives the 95% interval of the mean it reports;
benchmarks/pool_heldout.py pools held-out blocks from their summaries into what the episodes
themselves give, and counts a seed block once per policy."""

import math
from pathlib import Path

import numpy as np
import pytest

from .conftest import load_benchmark

pool_heldout = load_benchmark("pool_heldout")


def test_pooled_summaries_equal_the_statistics_of_all_episodes():
    rng = np.random.default_rng(0)
    blocks = [rng.normal(loc, 80.0, size=n) for loc, n in ((270, 100), (290, 200), (250, 37))]
    summaries = [(len(b), float(b.mean()), float(b.std())) for b in blocks]
    total, mean, std = pool_heldout.pool_blocks(summaries)
    everything = np.concatenate(blocks)
    assert total == everything.size
    assert mean == pytest.approx(everything.mean(), rel=1e-12)
    assert std == pytest.approx(everything.std(), rel=1e-12)
    lo, hi = pool_heldout.mean_interval(total, mean, std)
    assert hi - lo == pytest.approx(2 * 1.96 * everything.std() / math.sqrt(total - 1))


def test_the_eval_verdict_gives_the_interval_of_its_mean():
    from bipedal_cli.display import verdict
    from bipedal_cli.evaluation import summarize

    class Episode:
        def __init__(self, ret):
            self.ret, self.length, self.fell, self.fell_at = ret, 1000, ret < 0, None

    returns = [310.0, 305.0, 300.0, -50.0, 295.0]
    summary = summarize([Episode(r) for r in returns])
    half = 1.96 * np.std(returns) / 2.0  # sqrt(5 - 1)
    mean = np.mean(returns)
    assert verdict(summary) == (
        f"[bold red]not solved[/]: mean {mean:.1f} <= 300 "
        f"(95% interval {mean - half:.1f} to {mean + half:.1f})"
    )
    one = summarize([Episode(320.0)])
    assert verdict(one) == "[bold green]solved[/]: mean 320.0 > 300"  # no spread from one


def test_a_paired_difference_is_the_interval_of_the_per_seed_differences():
    from bipedal_cli.evaluation import EpisodeResult, paired_difference

    seeds = (7, 8, 9, 10)
    a = [EpisodeResult(s, r, 900, r < 0) for s, r in zip(seeds, (310, -40, 300, 305), strict=True)]
    b = [EpisodeResult(s, r, 900, r < 0) for s, r in zip(seeds, (300, 290, -60, 301), strict=True)]
    d = np.array([10.0, -330.0, 360.0, 4.0])
    diff = paired_difference(a, b)
    half = 1.96 * d.std() / math.sqrt(3)
    assert diff == pytest.approx(
        {"episodes": 4, "mean": d.mean(), "low": d.mean() - half, "high": d.mean() + half}
    )
    with pytest.raises(ValueError, match="different seeds"):
        paired_difference(a, b[::-1])


def test_wilson_interval_known_values():
    lo, hi = pool_heldout.wilson_interval(10, 100)  # textbook: 5.52% - 17.44%
    assert (lo, hi) == (pytest.approx(0.0552, abs=1e-4), pytest.approx(0.1744, abs=1e-4))
    lo, hi = pool_heldout.wilson_interval(0, 50)
    assert lo == pytest.approx(0.0, abs=1e-12) and 0 < hi < 0.08


def held(mean, falls, episodes=100):
    return {"episodes": episodes, "mean": mean, "std": 50.0, "falls": falls}


def row(path, step, mean, sha=None, episodes=100):
    out = {"path": str(path), "step": step, "held_out": held(mean, 10, episodes)}
    return out if sha is None else {**out, "sha256": sha}


def report(first, rows, confirm=None):
    out = {"seeds": [first, first + 99], "candidates": rows, "confirm": None}
    if confirm:
        out["confirm"] = {"seeds": [first + 100, first + 299], "finalists": confirm}
    return out


def test_a_block_counts_once_and_absolute_paths_match_relative_ones():
    shipped = Path.cwd() / "checkpoints" / "p.pt"
    first = report(10, [row(shipped, 5, 280.0)], confirm=[row("checkpoints/p.pt", 5, 270.0)])
    again = report(10, [row("checkpoints/p.pt", 5, 999.0), row("checkpoints/p.pt", 6, 250.0)])
    policies = pool_heldout.collect([first, again])
    places = {e["place"] for e in policies.values()}
    assert places == {("checkpoints/p.pt", 5), ("checkpoints/p.pt", 6)}
    (blocks,) = [e["blocks"] for e in policies.values() if e["place"][1] == 5]
    assert sorted(blocks) == [(10, 109), (110, 309)]
    assert blocks[(10, 109)]["mean"] == 280.0  # the first report's, not the repeat's


def test_the_file_digest_is_the_identity_and_old_rows_join_the_one_file_seen_there():
    old = report(10, [row("checkpoints/p.pt", 5, 280.0)])
    new = report(1000, [row("checkpoints/p.pt", 5, 270.0, sha="aa")])
    kept_copy = report(2000, [row("runs/r/policies/step-5.pt", 5, 260.0, sha="aa")])
    policies = pool_heldout.collect([old, new, kept_copy])
    assert list(policies) == ["aa"]  # one policy: the old row by name, the copy by content
    assert len(policies["aa"]["blocks"]) == 3

    reshipped = report(3000, [row("checkpoints/p.pt", 5, 300.0, sha="bb")])
    policies = pool_heldout.collect([old, new, reshipped])
    assert set(policies) == {"aa", "bb", "checkpoints/p.pt@5 (ambiguous)"}
    assert len(policies["aa"]["blocks"]) == len(policies["bb"]["blocks"]) == 1
