"""Restarts near recent falls (``train.fall_restart``): more of the learner's experience where
it fails.

A late Hardcore policy falls in about one training episode in ten, and each fall is decided in a
few policy steps at one obstacle, so the transitions that could teach it not to fall are a tiny
share of the replay buffer. An episode is a pure function of its env seed and its actions
(:mod:`bipedal_cli.episodes`), so the state shortly before a fall can be rebuilt exactly: reset
a new env with the fallen episode's seed and replay its actions up to k policy steps before the
end. With probability p a new training episode does that instead of starting afresh, then the
learner acts from there (for ``train.fall_restart_horizon`` policy steps, then a truncation).
The replayed prefix is not stored: its transitions are in the buffer already.

Only fresh episodes' falls are remembered (the last ``train.fall_restart_memory`` of them), so
the restarts follow where the current policy falls on terrain it has not seen, and a spot it
keeps failing at from a restart cannot crowd out the others. Evaluations are untouched.

With ``train.fall_restart_probe`` q > 0, a fresh episode is, with probability q, a probe played
by the deterministic policy (the one evaluations score), and only probes' falls are remembered:
the stochastic policy's falls are mostly its noise's (session 22: from 45 policy steps back the
deterministic policy avoided 98% of them), so restarts explore near the falls that cost the
score instead.
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np


def restarts_on(train: Any, step: int) -> bool:
    """Whether an episode starting after policy ``step`` may restart near a fall (and a fall
    ending there is remembered): after ``train.fall_restart_start``, so that a run branched at
    that step is, up to it, the run it branches from."""
    return train.fall_restart > 0 and step > train.fall_restart_start


def draws_probe(rng: np.random.Generator, train: Any, step: int) -> bool:
    """Whether a fresh episode starting after policy ``step`` is a probe (the deterministic
    policy's): with probability ``train.fall_restart_probe`` once restarts are on. Draws from
    ``rng`` only then, so that a run without probes is unchanged to the bit."""
    if not (restarts_on(train, step) and train.fall_restart_probe > 0):
        return False
    return bool(rng.random() < train.fall_restart_probe)


def remembers_fall(train: Any, step: int, fresh: bool, probe: bool, fell: bool) -> bool:
    """Whether a finished episode's fall is remembered for restarts: a fresh episode's, once
    restarts are on, and with probes on (``train.fall_restart_probe`` > 0) only a probe's."""
    if not (fresh and fell and restarts_on(train, step)):
        return False
    return probe or train.fall_restart_probe == 0


def restart_length(fall_length: int, back: int) -> int:
    """Policy steps replayed before the learner takes over: the fallen episode's ``fall_length``
    actions less ``back`` (at least 0: a restart from the episode's first step)."""
    return max(0, fall_length - back)


class FallMemory:
    """The seeds and actions of the last ``capacity`` fresh episodes that fell."""

    def __init__(self, capacity: int) -> None:
        self.falls: deque[tuple[int, np.ndarray]] = deque(maxlen=capacity)

    def __len__(self) -> int:
        return len(self.falls)

    def remember(self, seed: int, actions: list[np.ndarray] | np.ndarray, act_dim: int) -> None:
        self.falls.append((int(seed), np.array(actions, np.float32).reshape(-1, act_dim)))

    def draw(self, rng: np.random.Generator, train: Any) -> tuple[int, np.ndarray] | None:
        """With probability ``train.fall_restart`` (and at least one fall remembered), a fall
        drawn uniformly and a back-off k uniform in ``train.fall_restart_back_min`` ..
        ``train.fall_restart_back``: its seed and the actions to replay. None: a fresh
        episode. Draws nothing from ``rng`` when nothing is remembered, so that a run is the
        plain run to the bit up to its first fall."""
        if not self.falls or rng.random() >= train.fall_restart:
            return None
        seed, actions = self.falls[int(rng.integers(len(self.falls)))]
        back = int(rng.integers(train.fall_restart_back_min, train.fall_restart_back + 1))
        return seed, actions[: restart_length(len(actions), back)]

    def state_dict(self) -> list[dict[str, Any]]:
        import torch

        return [{"seed": s, "actions": torch.from_numpy(a.copy())} for s, a in self.falls]

    def load_state_dict(self, state: list[dict[str, Any]] | None) -> None:
        self.falls.clear()
        for fall in state or []:
            self.falls.append((int(fall["seed"]), fall["actions"].numpy().astype(np.float32)))
