"""Making BipedalWalker / Hardcore environments, with the policy's and the learner's wrappers.

Every env is ``gym.make(id)`` (the env's own reward and TimeLimit: 1,600 / 2,000 env steps)
wrapped, innermost first, by

1. :class:`RewardShaping` (always): reports the env's own reward and whether the step was a
   fall in ``info``; for training only, it can replace the -100 fall penalty and scale rewards;
2. :class:`ActionRepeat` (``agent.action_repeat`` = k > 1): the policy's action is held for k
   env steps and their rewards summed; the inner TimeLimit still counts env steps;
3. :class:`ObservationHistory` (``agent.history`` = H > 1): the policy sees its last H
   observations, oldest first, as one flat vector of H * 24.

2 and 3 are part of the policy (evaluation and recording use them too); 1 changes what the
learner sees only, so every score reported is on the env's own reward.
"""

from __future__ import annotations

import warnings
from collections import deque
from collections.abc import Callable

import gymnasium as gym
import numpy as np

from .env_ids import canonical_env_id
from .obstacle_mix import ObstacleMix

FALL_REWARD = -100.0  # BipedalWalker's reward on the step where the hull touches the ground


def is_fall(terminated: bool, reward: float) -> bool:
    """An env step that ended the episode on the fall penalty (as opposed to reaching the end)."""
    return bool(terminated and reward <= FALL_REWARD)


class RewardShaping(gym.Wrapper):
    """r' = scale * (fall_penalty if the step is a fall else r); ``info`` gets ``env_reward``
    (the env's own r), ``fell`` and ``env_steps`` (1).

    With ``fall_penalty=None`` and ``scale=1`` the reward passes through unchanged.
    """

    def __init__(self, env: gym.Env, fall_penalty: float | None = None, scale: float = 1.0):
        super().__init__(env)
        self.fall_penalty, self.scale = fall_penalty, scale

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        fell = is_fall(terminated, reward)
        info = {**info, "env_reward": float(reward), "fell": fell, "env_steps": 1}
        if fell and self.fall_penalty is not None:
            reward = self.fall_penalty
        if self.scale != 1.0:
            reward = self.scale * reward
        return obs, reward, terminated, truncated, info


class ActionRepeat(gym.Wrapper):
    """Hold each action for ``repeat`` env steps (fewer when the episode ends): the reward and
    ``info['env_reward']`` are the sums over those steps, ``info['env_steps']`` their number.
    ``on_env_step(env_reward)`` is called after each of them."""

    def __init__(
        self, env: gym.Env, repeat: int, on_env_step: Callable[[float], None] | None = None
    ):
        super().__init__(env)
        self.repeat, self.on_env_step = repeat, on_env_step

    def step(self, action):
        reward_sum, env_reward_sum, steps = 0.0, 0.0, 0
        while steps < self.repeat:
            obs, reward, terminated, truncated, info = self.env.step(action)
            steps += 1
            reward_sum += float(reward)
            env_reward_sum += float(info.get("env_reward", reward))
            if self.on_env_step is not None:  # recording: a frame per env step
                self.on_env_step(float(info.get("env_reward", reward)))
            if terminated or truncated:
                break
        info = {**info, "env_reward": env_reward_sum, "env_steps": steps}
        return obs, reward_sum, terminated, truncated, info


class ObservationHistory(gym.Wrapper):
    """The last ``length`` observations o_{t-H+1}, ..., o_t as one vector (H * obs_dim,);
    at reset the first observation fills the whole history."""

    def __init__(self, env: gym.Env, length: int):
        super().__init__(env)
        self.length = length
        space = env.observation_space
        self.observation_space = gym.spaces.Box(
            np.tile(space.low, length), np.tile(space.high, length), dtype=space.dtype
        )
        self._frames: deque[np.ndarray] = deque(maxlen=length)

    def _stacked(self) -> np.ndarray:
        return np.concatenate(self._frames)  # (H * obs_dim,), oldest first

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self._frames.extend([obs] * self.length)
        return self._stacked(), info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        self._frames.append(obs)
        return self._stacked(), reward, terminated, truncated, info


def make_env(
    env_id: str,
    render: bool = False,
    *,
    action_repeat: int = 1,
    history: int = 1,
    fall_penalty: float | None = None,
    reward_scale: float = 1.0,
    on_env_step: Callable[[float], None] | None = None,
    obstacle_weights: tuple[float, float, float] | None = None,
) -> gym.Env:
    """A Gymnasium env with its standard TimeLimit and the wrappers described above.

    ``render=True`` uses ``render_mode="rgb_array"``: frames come back as arrays, no window and
    no display are needed. ``on_env_step(env_reward)`` is called after every env step (also
    inside an action repeat). ``obstacle_weights`` (stump, stairs, pit; training only) builds
    Hardcore's courses with that mix (:class:`~bipedal_cli.obstacle_mix.ObstacleMix`, innermost).
    """
    env_id = canonical_env_id(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make(env_id, render_mode="rgb_array" if render else None)
    if obstacle_weights is not None:
        env = ObstacleMix(env, obstacle_weights)
    env = RewardShaping(env, fall_penalty, reward_scale)
    if action_repeat > 1 or on_env_step is not None:
        env = ActionRepeat(env, action_repeat, on_env_step)
    if history > 1:
        env = ObservationHistory(env, history)
    return env


def make_policy_env(
    env_id: str,
    agent_cfg,
    render: bool = False,
    on_env_step: Callable[[float], None] | None = None,
) -> gym.Env:
    """The env as the policy runs in it: the env's own reward, with the policy's action repeat
    and observation history (``agent_cfg``: an :class:`~bipedal_cli.config.AgentConfig`)."""
    return make_env(
        env_id,
        render,
        action_repeat=agent_cfg.action_repeat,
        history=agent_cfg.history,
        on_env_step=on_env_step,
    )


def env_dims(env: gym.Env) -> tuple[int, int]:
    return int(env.observation_space.shape[0]), int(env.action_space.shape[0])


def policy_dims(env_id: str, agent_cfg) -> tuple[int, int]:
    """(network input size, action size) of a policy for ``env_id``: (H * 24, 4)."""
    probe = make_policy_env(env_id, agent_cfg)
    try:
        return env_dims(probe)
    finally:
        probe.close()
