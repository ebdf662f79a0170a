"""The loop of a :class:`~bipedal_cli.train.Trainer`: one policy step at a time, the updates
after it (:func:`~bipedal_cli.scheduled_update.scheduled_updates`), periodic evaluations and
checkpoints, and the display's refresh, until the budget, a stop request or a passed test."""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from .episode_record import record_episode
from .metrics import MetricsWriter
from .periodic_eval import periodic_evaluation
from .refill import refill_actor
from .run_state import diverged
from .scheduled_update import scheduled_updates


class WallClock:
    """A run's wall time: the seconds of its earlier sessions plus this session's."""

    def __init__(self, earlier_s: float) -> None:
        self.earlier_s, self.start = earlier_s, time.perf_counter()

    def __call__(self) -> float:
        return self.earlier_s + time.perf_counter() - self.start


class StepRate:
    """Policy steps per second since the window's start; the window restarts once it is
    longer than ``window_s`` seconds, so the display follows the current speed."""

    def __init__(self, step: int, window_s: float = 5.0) -> None:
        self.window_s = window_s
        self.start, self.start_step = time.perf_counter(), step
        self.per_s = 0.0

    def update(self, step: int) -> float:
        now = time.perf_counter()
        self.per_s = (step - self.start_step) / max(now - self.start, 1e-9)
        if now - self.start > self.window_s:
            self.start, self.start_step = now, step
        return self.per_s


def train_until(
    trainer: Any, metrics: MetricsWriter, total: int, until_solved: bool
) -> tuple[str, float]:
    """Policy steps and updates until step ``total``, a stop request or (``until_solved``) a
    passed 100-episode test; returns how it stopped and the last steps per second."""
    t = trainer.cfg.train
    trainer.reporter.start(trainer.step, total)
    stopped = "budget"
    clock, rate = WallClock(trainer.wall_time), StepRate(trainer.step)
    if trainer.runner.obs is None:
        trainer.start_episode()
    try:
        while trainer.step < total:
            if trainer.stop_signal is not None:
                stopped = "interrupted"
                break
            env_step(trainer, metrics, clock)
            if trainer.learning():
                trainer.update_metrics = scheduled_updates(trainer) or trainer.update_metrics
            trainer.wall_time = clock()
            if t.eval_every and trainer.step % t.eval_every == 0:
                outcome = periodic_evaluation(trainer, metrics, until_solved)
                if outcome is not None:
                    stopped = outcome
                    break
            if t.checkpoint_every and trainer.step % t.checkpoint_every == 0:
                trainer.save()
            if trainer.step % 50 == 0:
                trainer.reporter.update(trainer.snapshot(rate.update(trainer.step)))
    finally:
        trainer.wall_time = clock()
    return stopped, rate.per_s


def env_step(trainer: Any, metrics: MetricsWriter, clock: WallClock) -> None:
    """One policy step: uniform random actions during the warm-up (unless ``train.init_policy``
    gives a policy to start from), else the actor's (its mean in a probe episode; a refill
    policy's in a restart's refill with ``train.refill_policies``); an episode
    that ends is booked and the next one started."""
    t = trainer.cfg.train
    if trainer.step < t.warmup_steps and t.init_policy is None:
        action = trainer.rng.uniform(-1.0, 1.0, trainer.act_dim).astype(np.float32)
    else:
        probe = trainer.runner.episode.probe
        action = trainer.agent.act(trainer.runner.obs, probe, actor=refill_actor(trainer))
        if not np.isfinite(action).all():  # Box2D must never see a NaN action
            raise diverged(trainer, "the policy's action")
    env_steps_before = trainer.runner.episode.env_steps
    finished = trainer.runner.step(action)
    trainer.step += 1
    trainer.env_steps += trainer.runner.episode.env_steps - env_steps_before
    if finished is not None:
        trainer.wall_time = clock()
        record_episode(trainer, finished, metrics)
        trainer.start_episode()
