"""The training env and the episode in progress: stepping, storing transitions, exact rebuild.

An episode is a pure function of its env seed and its actions: each episode gets a new env (a
reused Box2D world keeps history across resets: body and contact ordering), so resetting a fresh
env with the seed and replaying the actions rebuilds it exactly, wrappers' state included (the
observation history, the pending n-step steps). That is what exact resume relies on.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .buffer import ReplayBuffer
from .config import Config, TrainConfig
from .envs import make_env
from .nstep import NStepAccumulator


def curation_on(train: TrainConfig, step: int) -> bool:
    """Whether FORK's replay curation holds the transitions of an episode starting at ``step``."""
    return train.replay_keep_below is not None and step >= train.replay_curation_start


def curation_keeps(fell: bool, env_return: float, keep_below: float) -> bool:
    """FORK's rule: a curated episode enters the replay buffer only if it fell or its env return
    is below ``keep_below``."""
    return fell or env_return < keep_below


def obstacle_mix_on(train: TrainConfig, step: int) -> bool:
    """Whether an episode starting at ``step`` trains on a course with the obstacle mix
    (``train.obstacle_stump``, ``_stairs``, ``_pit`` unequal; :mod:`.obstacle_mix`)."""
    return train.mixes_obstacles() and step >= train.obstacle_mix_start


@dataclass
class EpisodeState:
    """The episode in progress: enough to rebuild the env exactly after a resume."""

    seed: int = 0
    actions: list[np.ndarray] = field(default_factory=list)
    ret: float = 0.0  # the learner's return (shaped rewards)
    env_ret: float = 0.0  # the env's own return
    env_steps: int = 0  # env steps (action repeat: several per action)
    curated: bool = False  # its transitions wait for its end, then are kept or dropped
    fall_penalty: float | None = None  # what the learner sees on a fall (None: the env's -100)
    restart_at: int | None = None  # a restart near a fall: the actions replayed, not stored
    restart_env_steps: int = 0  # and their env steps
    probe: bool = False  # played by the deterministic policy (train.fall_restart_probe)
    obstacle_mix: bool = False  # its course has train.obstacle_*'s mix of obstacles


@dataclass
class FinishedEpisode:
    ret: float
    env_ret: float
    env_steps: int
    fell: bool
    stored: bool = True  # False: replay curation dropped its transitions
    restart_env_steps: int | None = None  # a restart near a fall: the env steps replayed
    probe: bool = False  # played by the deterministic policy


class EpisodeRunner:
    """Steps the training env (shaping, action repeat, history as configured) and writes each
    transition to the replay buffer, through an n-step accumulator when ``agent.n_step`` > 1.

    A curated episode (``train.replay_keep_below``, FORK's replay curation) holds its
    transitions until it ends, then writes them only if it fell or its env return is below the
    threshold: the buffer fills with the episodes that went wrong.
    """

    def __init__(self, cfg: Config, buffer: ReplayBuffer) -> None:
        self.cfg, self.buffer = cfg, buffer
        n = cfg.agent.n_step
        self.nstep = NStepAccumulator(n, cfg.agent.gamma) if n > 1 else None
        self.episode = EpisodeState(fall_penalty=cfg.train.fall_penalty)
        self.env = self._make_env()
        self.obs: np.ndarray | None = None  # None: no episode in progress
        self.staged: list[tuple] = []  # a curated episode's transitions so far

    def _make_env(self):
        a, t = self.cfg.agent, self.cfg.train
        return make_env(
            self.cfg.env,
            action_repeat=a.action_repeat,
            history=a.history,
            fall_penalty=self.episode.fall_penalty,
            reward_scale=t.reward_scale,
            obstacle_weights=t.obstacle_weights() if self.episode.obstacle_mix else None,
        )

    def _fresh_env(self) -> None:
        self.env.close()
        self.env = self._make_env()  # follows cfg.env, which a curriculum switches

    def start(
        self,
        seed: int,
        curated: bool,
        fall_penalty: float | None,
        prefix: np.ndarray | None = None,
        probe: bool = False,
        obstacle_mix: bool = False,
    ) -> None:
        """A new episode on a new env reset with ``seed``; ``curated`` and ``fall_penalty`` hold
        to its end (:func:`curation_on` and :func:`~bipedal_cli.schedule.fall_penalty_at` at
        the step it starts). With ``prefix`` (a restart near a fall,
        :mod:`bipedal_cli.fall_restarts`) those actions are replayed first and nothing of them
        is stored: the learner takes over after them. A ``probe`` is played by the
        deterministic policy (the trainer reads it from :attr:`episode`); ``obstacle_mix``
        builds its course with the config's mix of obstacles (:func:`obstacle_mix_on`)."""
        self.episode = EpisodeState(
            seed=seed,
            curated=curated,
            fall_penalty=fall_penalty,
            probe=probe,
            obstacle_mix=obstacle_mix,
        )
        self._fresh_env()
        obs, _ = self.env.reset(seed=seed)
        self.obs = obs.astype(np.float32)
        self.staged = []
        if prefix is not None:
            for action in prefix:
                next_obs, reward, _, _, info = self.env.step(action)
                self._account(action, reward, info)
                self.obs = next_obs.astype(np.float32)
            e = self.episode
            e.restart_at, e.restart_env_steps = len(prefix), e.env_steps
        if self.nstep is not None:
            self.nstep.reset()

    def _cut(self, truncated: bool) -> bool:
        """A restarted episode is truncated ``train.fall_restart_horizon`` policy steps after it
        took over (counting the step being taken)."""
        e, horizon = self.episode, self.cfg.train.fall_restart_horizon
        if e.restart_at is None or horizon is None:
            return truncated
        return truncated or len(e.actions) + 1 - e.restart_at >= horizon

    def step(self, action: np.ndarray) -> FinishedEpisode | None:
        """One policy step: env step(s), the transition stored; the result when it ended."""
        next_obs, reward, terminated, truncated, info = self.env.step(action)
        truncated = self._cut(truncated)
        self._store(action, reward, next_obs, terminated, truncated)
        self._account(action, reward, info)
        self.obs = next_obs.astype(np.float32)
        if terminated or truncated:
            e, fell = self.episode, bool(info["fell"])
            stored = not e.curated or curation_keeps(
                fell, e.env_ret, self.cfg.train.replay_keep_below
            )
            if e.curated and stored:
                for transition in self.staged:
                    self.buffer.add(*transition)
            self.staged = []
            replayed = None if e.restart_at is None else e.restart_env_steps
            return FinishedEpisode(e.ret, e.env_ret, e.env_steps, fell, stored, replayed, e.probe)
        return None

    def _account(self, action: np.ndarray, reward: float, info: dict) -> None:
        e = self.episode
        e.actions.append(action)
        e.ret += float(reward)
        e.env_ret += float(info["env_reward"])
        e.env_steps += int(info["env_steps"])

    def _store(self, action, reward, next_obs, terminated: bool, truncated: bool) -> None:
        if self.nstep is None:  # terminated, never truncated: a truncation bootstraps
            ready = [(self.obs, action, reward, next_obs, terminated)]
        else:
            pushed = self.nstep.push(self.obs, action, reward, next_obs, terminated, truncated)
            ready = [
                (tr.obs, tr.action, tr.reward, tr.next_obs, tr.terminated, tr.discount)
                for tr in pushed
            ]
        if self.episode.curated:
            self.staged.extend(ready)
            return
        for transition in ready:
            self.buffer.add(*transition)

    def replay(
        self,
        seed: int,
        actions: np.ndarray,
        expected_obs: np.ndarray,
        curated: bool,
        fall_penalty: float | None,
        restart_at: int | None = None,
        probe: bool = False,
        obstacle_mix: bool = False,
    ) -> bool:
        """Rebuild an interrupted episode (its transitions are in the buffer already, or, when
        curated, staged again; a restart's first ``restart_at`` actions are replayed as its
        start replayed them); False when the rebuilt observation differs from
        ``expected_obs``."""
        prefix = None if restart_at is None else actions[:restart_at]
        self.start(seed, curated, fall_penalty, prefix, probe, obstacle_mix)
        for action in actions[restart_at or 0 :]:
            next_obs, reward, terminated, truncated, info = self.env.step(action)
            truncated = self._cut(truncated)
            if curated:
                self._store(action, reward, next_obs, terminated, truncated)
            elif self.nstep is not None:  # the pending steps only; what it returns is stored
                self.nstep.push(self.obs, action, reward, next_obs, terminated, truncated)
            self._account(action, reward, info)
            self.obs = next_obs.astype(np.float32)
        return bool(np.array_equal(self.obs, expected_obs))

    def state_dict(self, act_dim: int) -> dict:
        import torch

        e = self.episode
        return {
            "seed": e.seed,
            "actions": torch.from_numpy(np.array(e.actions, np.float32).reshape(-1, act_dim)),
            "ret": e.ret,  # rebuilt by replay; kept as older versions read it
            "curated": e.curated,
            "fall_penalty": e.fall_penalty,
            "restart_at": e.restart_at,
            "probe": e.probe,
            "obstacle_mix": e.obstacle_mix,
            "obs": None if self.obs is None else torch.from_numpy(self.obs.copy()),
        }
