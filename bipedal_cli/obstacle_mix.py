"""Training courses with more of some obstacle kinds: a curriculum over stumps, stairs and pits.

BipedalWalkerHardcore-v3 builds its course at reset: grass, then after each stretch of grass an
obstacle drawn uniformly from stump, stairs and pit by the env's own generator, as
``np_random.integers(1, 4)`` (1 stump, 2 stairs, 3 pit; grass is 0; Gymnasium 1.x
``bipedal_walker._generate_terrain``). :class:`ObstacleMix` seeds the env itself and hands it
a generator that answers exactly that draw with a weighted one,

    P(kind) = w_kind / (w_stump + w_stairs + w_pit),

and passes every other draw (heights, sizes, lengths, the hull's push) to the seeded generator
unchanged. It changes only what the learner trains on: evaluations and every reported score use
the unmodified env. ``tests/test_obstacle_mix.py`` checks the courses it builds with
:mod:`bipedal_cli.terrain`, so a Gymnasium that draws the kind differently fails there.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.utils import seeding

KIND_DRAW = (1, 4)  # integers(1, _STATES_): STUMP 1, STAIRS 2, PIT 3 (GRASS 0, _STATES_ 4)
KIND_CODES = (1, 2, 3)  # stump, stairs, pit


def kind_probabilities(weights: Sequence[float]) -> np.ndarray:
    """(3,) probabilities of stump, stairs, pit from non-negative weights with a positive sum
    (the unmodified env: 1/3 each)."""
    w = np.asarray(weights, dtype=np.float64)
    if w.shape != (3,) or (w < 0).any() or w.sum() <= 0:
        raise ValueError(f"expected three non-negative weights with a positive sum, got {weights}")
    return w / w.sum()


class WeightedKindGenerator:
    """A numpy Generator whose ``integers(1, 4)`` is the weighted obstacle kind; every other
    call goes to ``rng``."""

    def __init__(self, rng: np.random.Generator, probabilities: np.ndarray) -> None:
        self._rng, self._p = rng, probabilities

    def integers(self, low: Any, high: Any = None, *args: Any, **kwargs: Any) -> Any:
        if (low, high) == KIND_DRAW and not args and not kwargs:
            return np.int64(KIND_CODES[int(self._rng.choice(3, p=self._p))])
        return self._rng.integers(low, high, *args, **kwargs)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._rng, name)


class ObstacleMix(gym.Wrapper):
    """Reset with ``seed``: the env's generator is ``seeding.np_random(seed)`` (what the env's
    own reset would make) behind :class:`WeightedKindGenerator`, so a seed fixes the course."""

    def __init__(self, env: gym.Env, weights: Sequence[float]) -> None:
        super().__init__(env)
        self.probabilities = kind_probabilities(weights)

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        base = self.env.unwrapped
        if seed is not None or not isinstance(base.np_random, WeightedKindGenerator):
            rng, _ = seeding.np_random(seed)
            base.np_random = WeightedKindGenerator(rng, self.probabilities)
        return self.env.reset(seed=None, options=options)
