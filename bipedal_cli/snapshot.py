"""What the live display shows of a training run: a plain dict built from the trainer's
counters (:func:`training_snapshot`), and the statistics over its recent episodes."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from .episodes import curation_keeps, curation_on, obstacle_mix_on
from .fall_restarts import restarts_on
from .obstacle_mix import kind_probabilities
from .recency import recency_at
from .schedule import (
    actor_frozen,
    actor_lowest_atoms,
    actor_smooth_at,
    batch_size_at,
    drop_per_critic_at,
    target_entropy_at,
    updates_at,
)


def replay_kept_share(
    returns: Sequence[float], falls: Sequence[bool], keep_below: float | None
) -> float | None:
    """The share of recent episodes that FORK's replay curation let into the replay buffer:
    those that fell or whose env return is below ``keep_below``. None without curation or
    without episodes."""
    if keep_below is None or not returns:
        return None
    return float(
        np.mean([curation_keeps(f, r, keep_below) for r, f in zip(returns, falls, strict=True)])
    )


def training_snapshot(trainer: Any, steps_per_s: float) -> dict[str, Any]:
    """The display's view of a :class:`~bipedal_cli.train.Trainer` (its losses already read)."""
    recent, falls, t = list(trainer.recent_returns), list(trainer.recent_falls), trainer.cfg.train
    a = trainer.cfg.agent
    last_eval = trainer.last_eval
    curating = curation_on(t, trainer.step)
    return {
        "phase": (
            "warm-up"
            if trainer.step < t.warmup_steps
            else refill_phase(t)  # restarted from a restart.pt: acting, no updates yet
            if trainer.step < trainer.refill_until
            else "critics only"  # agent.actor_update_start: the actor and alpha wait
            if actor_frozen(trainer.step, trainer.cfg.agent)
            else "training"
        ),
        "step": trainer.step,
        "episodes": trainer.episodes,
        "steps_per_s": steps_per_s,
        "last_return": recent[-1] if recent else None,
        "avg_return": float(np.mean(recent[-10:])) if recent else None,
        "last_eval": last_eval["mean"] if last_eval else None,
        "last_eval_falls": (f"{last_eval['falls']}/{last_eval['episodes']}" if last_eval else None),
        "fall_rate": sum(falls) / len(falls) if falls else None,
        "falls_over": len(falls),
        "replay_kept": replay_kept_share(recent, falls, t.replay_keep_below if curating else None),
        "wall_time": trainer.wall_time,
        "lr": trainer.agent.learning_rate(),
        # with a ramp (train.fall_penalty_final), the penalty of the episode in progress
        "fall_penalty": (
            trainer.runner.episode.fall_penalty if t.fall_penalty_final is not None else None
        ),
        # agent.actor_cvar, once the risk-averse objective is on
        "actor_cvar": (
            trainer.cfg.agent.actor_cvar
            if actor_lowest_atoms(trainer.step, trainer.cfg.agent) is not None
            else None
        ),
        # agent.batch_size_final: transitions per update, once a schedule changes them
        "batch_size": (
            batch_size_at(trainer.step, trainer.cfg.agent)
            if trainer.cfg.agent.batch_size_final is not None
            else None
        ),
        # agent.drop_per_critic_final: atoms each critic's targets drop, once a schedule changes it
        "drop_per_critic": (
            drop_per_critic_at(trainer.step, a) if a.drop_per_critic_final is not None else None
        ),
        # agent.target_entropy_final: H_T along its decay
        "target_entropy": (
            target_entropy_at(trainer.step, a, trainer.agent.act_dim)
            if a.target_entropy_final is not None
            else None
        ),
        # agent.actor_smooth: the weight of the actor's smoothness term, once it is on
        "actor_smooth": actor_smooth_at(trainer.step, a),
        # train.updates_per_step_final: updates per policy step, once a schedule changes them
        "updates_per_step": (
            updates_at(trainer.step, t) if t.updates_per_step_final is not None else None
        ),
        # train.replay_recency: ERE's eta at this step (1: uniform replay again)
        "replay_recency": recency_at(trainer.step, t),
        # train.obstacle_*: the share of each obstacle kind on the learner's new courses
        "obstacle_mix": (
            kind_probabilities(t.obstacle_weights()) if obstacle_mix_on(t, trainer.step) else None
        ),
        # train.fall_restart: the falls that episodes may restart near
        "falls_remembered": len(trainer.fall_memory) if restarts_on(t, trainer.step) else None,
        **trainer.last_metrics,
    }


def refill_phase(t: Any) -> str:
    """The display's phase while a restart refills its buffer, with how many policies play."""
    n = len(t.refill_policies)
    return f"refilling replay ({n} policies in turn)" if n else "refilling replay"
