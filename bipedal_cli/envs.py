"""Making BipedalWalker / Hardcore environments, off-screen when rendering."""

from __future__ import annotations

import warnings

import gymnasium as gym

from .config import canonical_env_id

FALL_REWARD = -100.0  # BipedalWalker's reward on the step where the hull touches the ground


def make_env(env_id: str, render: bool = False) -> gym.Env:
    """A Gymnasium env with its standard TimeLimit (1600 / 2000 steps).

    ``render=True`` uses ``render_mode="rgb_array"``: frames come back as arrays, no window and
    no display are needed.
    """
    env_id = canonical_env_id(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gym.make(env_id, render_mode="rgb_array" if render else None)


def env_dims(env: gym.Env) -> tuple[int, int]:
    return int(env.observation_space.shape[0]), int(env.action_space.shape[0])


def is_fall(terminated: bool, reward: float) -> bool:
    """An episode that terminated on the fall penalty (as opposed to reaching the end)."""
    return bool(terminated and reward <= FALL_REWARD)
