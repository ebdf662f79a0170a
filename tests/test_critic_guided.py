"""benchmarks/critic_guided.py scores candidate actions by the mean of their L lowest pooled
atoms; L is the actor's own count for the CVaR fraction (schedule.actor_lowest_atoms)."""

import math
from types import SimpleNamespace

import torch

from bipedal_cli.schedule import actor_lowest_atoms

from .conftest import load_benchmark

critic_guided = load_benchmark("critic_guided")


def reference_lowest_mean(atoms, fraction):
    """Straight from the definition, one row at a time in float64."""
    out = []
    for row in atoms.tolist():
        pooled = sorted(x for critic in row for x in critic)
        lowest = max(1, math.floor(fraction * len(pooled) + 0.5))
        out.append(sum(pooled[:lowest]) / lowest)
    return out


def test_lowest_atoms_mean_matches_the_definition_with_the_actors_count():
    atoms = torch.randn(7, 5, 25, generator=torch.Generator().manual_seed(0), dtype=torch.float64)
    for c in (0.1, 0.25, 0.5, 0.001, 1.0):
        cfg = SimpleNamespace(actor_cvar=c, actor_cvar_start=0, n_critics=5, n_quantiles=25)
        got = critic_guided.lowest_atoms_mean(atoms, actor_lowest_atoms(1, cfg))
        assert torch.allclose(got, torch.tensor(reference_lowest_mean(atoms, c), dtype=got.dtype))
