"""The env wrappers (shaping, action repeat, history) on a tiny fake env: no Box2D needed."""

import gymnasium as gym
import numpy as np
import pytest

from bipedal_cli.envs import ActionRepeat, ObservationHistory, RewardShaping, make_env


class Corridor(gym.Env):
    """obs [t, 10 t]; reward t + 1 per step; falls (reward -100, terminated) at step ``fall_at``."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (2,), np.float32)
    action_space = gym.spaces.Box(-1, 1, (1,), np.float32)

    def __init__(self, fall_at=None):
        self.fall_at, self.t = fall_at, 0

    def reset(self, seed=None, options=None):
        self.t = 0
        return np.array([0, 0], np.float32), {}

    def step(self, action):
        self.t += 1
        fell = self.t == self.fall_at
        reward = -100.0 if fell else float(self.t)
        return np.array([self.t, 10 * self.t], np.float32), reward, fell, False, {}


def test_shaping_replaces_the_fall_penalty_then_scales_and_reports_the_env_reward():
    env = RewardShaping(Corridor(fall_at=2), fall_penalty=-5.0, scale=3.0)
    env.reset()
    _, r, term, _, info = env.step(0)
    assert (r, info["env_reward"], info["fell"]) == (3.0, 1.0, False)
    _, r, term, _, info = env.step(0)
    assert term and info["fell"]
    assert (r, info["env_reward"]) == (-15.0, -100.0)


def test_unshaped_reward_passes_through_unchanged():
    env = RewardShaping(Corridor(fall_at=1))
    env.reset()
    _, r, _, _, info = env.step(0)
    assert r == info["env_reward"] == -100.0 and info["fell"]


def test_action_repeat_sums_rewards_and_stops_at_the_episode_end():
    env = ActionRepeat(RewardShaping(Corridor(fall_at=5), fall_penalty=-1.0), 3)
    env.reset()
    obs, r, term, _, info = env.step(0)
    assert obs[0] == 3 and r == 1 + 2 + 3 and info["env_steps"] == 3 and not term
    obs, r, term, _, info = env.step(0)  # steps 4 and 5: the fall ends it after 2
    assert term and obs[0] == 5 and info["env_steps"] == 2
    assert r == 4 - 1.0 and info["env_reward"] == 4 - 100.0 and info["fell"]


def test_action_repeat_keeps_the_env_time_limit_in_env_steps():
    env = ActionRepeat(RewardShaping(gym.wrappers.TimeLimit(Corridor(), 7)), 3)
    env.reset()
    lengths = []
    truncated = False
    while not truncated:
        _, _, _, truncated, info = env.step(0)
        lengths.append(info["env_steps"])
    assert lengths == [3, 3, 1]


def test_history_stacks_the_last_observations_oldest_first():
    env = ObservationHistory(RewardShaping(Corridor()), 3)
    assert env.observation_space.shape == (6,)
    obs, _ = env.reset()
    assert obs.tolist() == [0, 0] * 3  # the first observation fills the history
    env.step(0)
    obs, *_ = env.step(0)
    assert obs.tolist() == [0, 0, 1, 10, 2, 20]
    obs, *_ = env.step(0)
    assert obs.tolist() == [1, 10, 2, 20, 3, 30]


@pytest.mark.parametrize("repeat,history", [(1, 1), (3, 4)])
def test_policy_env_of_bipedal_walker(repeat, history):
    env = make_env("walker", action_repeat=repeat, history=history)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (24 * history,) == env.observation_space.shape
    _, _, _, _, info = env.step(np.zeros(4, np.float32))
    assert info["env_steps"] == repeat
    env.close()
