"""n-step transitions from a stream of one-step ones (pure Python and NumPy; no env, no torch).

A transition stored for time t with n-step returns is (s_t, a_t, R_t, s_{t+m}, d, g) with

    R_t = sum_{j<m} gamma^j r_{t+j},      g = gamma^m (1 - d),

where m = n, or fewer when the episode ends first; d = 1 only when the episode *terminated*
inside those m steps (a fall or the finish). A time-limit truncation cuts the sum at the last
step but keeps the bootstrap (d = 0), because the state it cuts off still has a future. The
target is then y_i = R_t + g (z_(i)(s_{t+m}, a') - alpha log pi(a'|s_{t+m})).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np


@dataclass
class NStepTransition:
    obs: np.ndarray
    action: np.ndarray
    reward: float  # R_t
    next_obs: np.ndarray  # s_{t+m}
    terminated: bool  # d
    discount: float  # gamma^m (1 - d)


class NStepAccumulator:
    """Holds the last n - 1 steps of the episode in progress; :meth:`push` returns the
    transitions that became complete (none, one, or all the pending ones at an episode's end)."""

    def __init__(self, n: int, gamma: float) -> None:
        self.n, self.gamma = n, gamma
        self.pending: deque[tuple[np.ndarray, np.ndarray, float]] = deque()

    def reset(self) -> None:
        """Forget the pending steps (a new episode starts)."""
        self.pending.clear()

    def push(
        self,
        obs: np.ndarray,
        action: np.ndarray,
        reward: float,
        next_obs: np.ndarray,
        terminated: bool,
        truncated: bool,
    ) -> list[NStepTransition]:
        self.pending.append((obs, action, float(reward)))
        ready = []
        if len(self.pending) == self.n:
            ready.append(self._oldest(next_obs, terminated))
        if terminated or truncated:
            while self.pending:
                ready.append(self._oldest(next_obs, terminated))
        return ready

    def _oldest(self, next_obs: np.ndarray, terminated: bool) -> NStepTransition:
        """The oldest pending step as an m-step transition ending at ``next_obs``; dropped."""
        m = len(self.pending)
        ret = sum(self.gamma**j * r for j, (_, _, r) in enumerate(self.pending))
        obs, action, _ = self.pending.popleft()
        discount = 0.0 if terminated else self.gamma**m
        return NStepTransition(obs, action, ret, next_obs, bool(terminated), discount)
