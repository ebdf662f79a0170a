"""Intervals on scores: `bipedal eval`'s verdict gives the 95% interval of the mean it reports;
benchmarks/pool_heldout.py pools held-out blocks from their summaries into what the episodes
themselves give, and counts a seed block once per policy."""

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest

SCRIPT = Path(__file__).resolve().parent.parent / "benchmarks" / "pool_heldout.py"
spec = importlib.util.spec_from_file_location("pool_heldout", SCRIPT)
pool_heldout = importlib.util.module_from_spec(spec)
spec.loader.exec_module(pool_heldout)


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


def test_wilson_interval_known_values():
    lo, hi = pool_heldout.wilson_interval(10, 100)  # textbook: 5.52% - 17.44%
    assert (lo, hi) == (pytest.approx(0.0552, abs=1e-4), pytest.approx(0.1744, abs=1e-4))
    lo, hi = pool_heldout.wilson_interval(0, 50)
    assert lo == pytest.approx(0.0, abs=1e-12) and 0 < hi < 0.08


def held(mean, falls, episodes=100):
    return {"episodes": episodes, "mean": mean, "std": 50.0, "falls": falls}


def test_a_block_counts_once_and_absolute_paths_match_relative_ones():
    shipped = Path.cwd() / "checkpoints" / "p.pt"
    first = {
        "seeds": [10, 109],
        "candidates": [{"path": str(shipped), "step": 5, "held_out": held(280.0, 9)}],
        "confirm": {
            "seeds": [110, 309],
            "finalists": [{"path": "checkpoints/p.pt", "step": 5, "held_out": held(270, 20, 200)}],
        },
    }
    again = {  # the same first block in another report, and another policy step of the path
        "seeds": [10, 109],
        "candidates": [
            {"path": "checkpoints/p.pt", "step": 5, "held_out": held(999.0, 0)},
            {"path": "checkpoints/p.pt", "step": 6, "held_out": held(250.0, 30)},
        ],
        "confirm": None,
    }
    policies = pool_heldout.collect([first, again])
    assert set(policies) == {("checkpoints/p.pt", 5), ("checkpoints/p.pt", 6)}
    blocks = policies[("checkpoints/p.pt", 5)]
    assert sorted(blocks) == [(10, 109), (110, 309)]
    assert blocks[(10, 109)]["mean"] == 280.0  # the first report's, not the repeat's
