"""The learning after one policy step: every schedule of :mod:`bipedal_cli.schedule` applied to
the agent for that step, then U(t) TQC updates on fresh batches (``train.updates_per_step``, or
``train.updates_per_step_final`` after its step)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import torch

from .adam_moments import estimate_moments, moments_missing
from .recency import recency_at, recent_window
from .schedule import (
    actor_frozen,
    actor_lowest_atoms,
    actor_smooth_at,
    batch_size_at,
    drop_per_critic_at,
    scheduled_learning_rate,
    target_entropy_at,
    updates_at,
)


def scheduled_updates(trainer: Any) -> Mapping[str, torch.Tensor] | None:
    """The updates after policy step t = ``trainer.step``: learning rate lr(t), the actor's
    lowest atoms L(t), whether the actor waits, its smoothness weight, the target entropy
    H_T(t) and the targets' truncation k(t), then U(t) updates of B(t) transitions each,
    drawn from the replay buffer with the trainer's generator (uniformly, or with ERE's emphasis on
    recent transitions: :mod:`bipedal_cli.recency`). Returns the last update's
    metrics (unsynced; None when U(t) is 0)."""
    agent, cfg, step = trainer.agent, trainer.cfg, trainer.step
    lr = scheduled_learning_rate(step, cfg.agent)
    if lr is not None:
        agent.set_learning_rate(lr)
    agent.actor_lowest_atoms = actor_lowest_atoms(step, cfg.agent)
    agent.actor_frozen = actor_frozen(step, cfg.agent)
    agent.actor_smooth = actor_smooth_at(step, cfg.agent)
    agent.target_entropy = target_entropy_at(step, cfg.agent, agent.act_dim)
    agent.set_truncation(drop_per_critic_at(step, cfg.agent))
    batch_size = batch_size_at(step, cfg.agent)
    if trainer.refill_until and moments_missing(agent):  # restarted from a restart file
        estimate_moments(trainer, batch_size)
    eta = recency_at(step, cfg.train)
    metrics = None
    for _ in range(updates_at(step, cfg.train)):
        metrics = agent.update(agent.batch_to_tensors(draw_batch(trainer, batch_size, eta)))
    return metrics


def draw_batch(trainer: Any, batch_size: int, eta: float | None) -> dict[str, Any]:
    """B transitions for the next update: uniform over the replay buffer, or with ERE
    (``eta`` not None) uniform over its c_k newest (:func:`~bipedal_cli.recency.recent_window`,
    k from the agent's update counter)."""
    buffer = trainer.buffer
    if eta is None:
        return buffer.sample(batch_size, trainer.rng)
    c_min = trainer.cfg.train.replay_recent_min
    window = recent_window(len(buffer), eta, trainer.agent.updates, c_min)
    return buffer.sample_recent(batch_size, window, trainer.rng)
