"""Preallocated float32 ring replay buffer (numpy; no torch, no environment)."""

from __future__ import annotations

import numpy as np

FIELDS = ("obs", "action", "reward", "next_obs", "terminated")


class ReplayBuffer:
    """Fixed-capacity FIFO of transitions (s, a, r, s', terminated).

    ``terminated`` is 1.0 only when the episode really ended (fall or finish); time-limit
    truncations are stored as 0.0 so that their targets bootstrap. ``with_discount`` adds a
    ``discount`` field, gamma^m (1 - terminated), for n-step transitions (:mod:`.nstep`).
    """

    def __init__(
        self, capacity: int, obs_dim: int, act_dim: int, with_discount: bool = False
    ) -> None:
        self.capacity, self.obs_dim, self.act_dim = capacity, obs_dim, act_dim
        self.fields = FIELDS + (("discount",) if with_discount else ())
        self.discount = np.zeros((capacity,), np.float32) if with_discount else None
        self.obs = np.zeros((capacity, obs_dim), np.float32)
        self.action = np.zeros((capacity, act_dim), np.float32)
        self.reward = np.zeros((capacity,), np.float32)
        self.next_obs = np.zeros((capacity, obs_dim), np.float32)
        self.terminated = np.zeros((capacity,), np.float32)
        self.pos = 0  # next slot to write
        self.size = 0  # filled slots

    def __len__(self) -> int:
        return self.size

    def add(
        self, obs, action, reward: float, next_obs, terminated: bool, discount: float = 0.0
    ) -> None:
        i = self.pos
        if self.discount is not None:
            self.discount[i] = discount
        self.obs[i] = obs
        self.action[i] = action
        self.reward[i] = reward
        self.next_obs[i] = next_obs
        self.terminated[i] = float(terminated)
        self.pos = (i + 1) % self.capacity
        self.size = min(self.size + 1, self.capacity)

    def sample(self, batch_size: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
        """Uniform sample with replacement: obs (B, obs_dim), action (B, act_dim), reward (B,)..."""
        if self.size == 0:
            raise ValueError("cannot sample from an empty replay buffer")
        idx = rng.integers(0, self.size, size=batch_size)
        return {name: getattr(self, name)[idx] for name in self.fields}

    def sample_recent(
        self, batch_size: int, window: int, rng: np.random.Generator
    ) -> dict[str, np.ndarray]:
        """Uniform sample with replacement from the ``window`` newest transitions (ERE,
        :mod:`.recency`): j ~ U{0 .. window - 1}, slot (pos - 1 - j) mod capacity."""
        if not 1 <= window <= self.size:
            raise ValueError(f"window {window} is not in [1, {self.size}] (the stored transitions)")
        age = rng.integers(0, window, size=batch_size)  # (B,): 0 is the newest transition
        idx = (self.pos - 1 - age) % self.capacity
        return {name: getattr(self, name)[idx] for name in self.fields}

    def state_dict(self) -> dict:
        """The filled slots in storage order plus the write position.

        Storage order (not chronological order) is kept so that the same sampled indices pick
        the same transitions after a resume.
        """
        data = {name: getattr(self, name)[: self.size].copy() for name in self.fields}
        return {"capacity": self.capacity, "size": self.size, "pos": self.pos, **data}

    def load_state_dict(self, state: dict) -> None:
        """Restore ``state``; one saved at another capacity loads only if it never wrapped and
        fits (:func:`fits_resized`), and then sits where a run of this capacity would hold it."""
        size, pos = int(state["size"]), int(state["pos"])
        saved_capacity = int(state.get("capacity", self.capacity))
        if saved_capacity != self.capacity:
            if not fits_resized(size, pos, saved_capacity, self.capacity):
                raise ValueError(
                    f"buffer state (size {size}, pos {pos}, capacity {saved_capacity}) has "
                    f"wrapped or does not fit capacity {self.capacity}"
                )
            pos = size % self.capacity
        if size > self.capacity or not 0 <= pos < self.capacity:
            raise ValueError(
                f"buffer state (size {size}, pos {pos}) does not fit capacity {self.capacity}"
            )
        for name in self.fields:
            getattr(self, name)[:size] = state[name]
        self.size, self.pos = size, pos


def fits_resized(size: int, pos: int, capacity: int, new_capacity: int) -> bool:
    """Whether a ring of ``capacity`` holding ``size`` transitions at write position ``pos`` is
    also what a ring of ``new_capacity`` would hold after the same additions.

    A ring that never overwrote a slot (pos == size < capacity) holds transition i in slot i, as
    any ring of at least ``size`` slots does, and sampling reads only the size. A full ring with
    pos 0 may have wrapped, so it does not count.
    """
    return pos == size < capacity and size <= new_capacity
