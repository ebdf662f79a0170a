"""Emphasizing Recent Experience (ERE; Wang and Ross 2019, arXiv:1906.04009), for one update per
policy step.

ERE draws the k-th of K updates after an episode uniformly from the most recent c_k of the N
stored transitions,

    c_k = max(N eta^(k 1000 / K), c_min),

so an update sequence runs from nearly the whole buffer to its newest part, and anneals eta
linearly from eta_0 to 1 (uniform replay) over training. Here updates follow every policy step,
not every episode, so the index k cycles through 1..K with K = 1000 over the updates themselves
(the agent's update counter): every 1000 updates make one ERE sequence, whatever the episodes'
lengths. Each value is a pure function of the policy step and the update counter, so ERE adds
nothing to a checkpoint and a resumed run follows it exactly.
"""

from __future__ import annotations

import math
from typing import Any

from .schedule import linear_ramp

SEQUENCE = 1000  # K: updates per ERE sequence (the paper's exponent k 1000 / K is then k)


def recency_at(step: int, train_cfg: Any) -> float | None:
    """eta(t) for the updates after policy step ``step``:

        eta(t) = eta_0 + (1 - eta_0) min(t / T, 1)    T = train.replay_recency_end
        eta(t) = eta_0                                T null

    None (uniform replay, ERE off) when ``train.replay_recency`` is None."""
    t = train_cfg
    if t.replay_recency is None:
        return None
    if t.replay_recency_end is None:
        return t.replay_recency
    return linear_ramp(step, t.replay_recency, 1.0, 0, t.replay_recency_end)


def recent_window(size: int, eta: float, update_index: int, c_min: int) -> int:
    """c_k: how many of the newest of ``size`` stored transitions update ``update_index`` (the
    agent's count of updates before it, from 0) draws from,

        c_k = min(N, max(floor(N eta^k), c_min)),   k = 1 + (update_index mod 1000).
    """
    if size <= 0:
        raise ValueError("cannot draw from an empty replay buffer")
    k = 1 + update_index % SEQUENCE
    return min(size, max(math.floor(size * eta**k), c_min))
