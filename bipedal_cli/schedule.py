"""Schedules over policy steps: constant, or linear over a window, for the learning rate, the
fall penalty the learner sees and the target entropy; from a step on, for the actor's
risk-averse objective and smoothness term, the targets' truncation, the batch size and the
actor's learning at all.

rl-zoo's tuned TQC for BipedalWalkerHardcore-v3 decays its learning rate linearly over the run;
ours is constant unless ``agent.lr_final`` is set. The fall penalty is constant unless
``train.fall_penalty_final`` is set, the target entropy unless ``agent.target_entropy_final``
is. Each is a pure function of the policy step, so it adds
nothing to a checkpoint and a resumed run follows it exactly.
"""

from __future__ import annotations

import math
from typing import Any


def learning_rate_at(step: int, lr: float, final: float | None, start: int, end: int) -> float:
    """The learning rate after ``step`` policy steps.

        lr(t) = lr                                          t <= start
        lr(t) = lr + (final - lr) (t - start) / (end - start)  start < t < end
        lr(t) = final                                       t >= end

    ``final`` None is the constant schedule, lr(t) = lr. Before ``start`` the value is ``lr``
    itself (no arithmetic), so a run that switches the decay on at a step it has not reached
    yet is, up to that step, the same run to the bit.
    """
    return linear_ramp(step, lr, final, start, end)


def linear_ramp(step: int, first: float, final: float | None, start: int, end: int) -> float:
    """``first`` up to ``start``, ``final`` from ``end`` on, linear in between (see
    :func:`learning_rate_at`); ``final`` None: always ``first``. ``end`` == ``start`` is a step."""
    if final is None or step <= start:
        return first
    if step >= end:
        return final
    return first + (final - first) * (step - start) / (end - start)


def scheduled_learning_rate(step: int, agent_cfg: Any) -> float | None:
    """``learning_rate_at`` for an :class:`~bipedal_cli.config.AgentConfig`; None when its
    schedule is constant (the optimizers keep ``agent.lr`` and are never touched)."""
    if agent_cfg.lr_final is None:
        return None
    return learning_rate_at(
        step, agent_cfg.lr, agent_cfg.lr_final, agent_cfg.lr_decay_start, agent_cfg.lr_decay_end
    )


def actor_lowest_atoms(step: int, agent_cfg: Any) -> int | None:
    """How many of the N*M pooled atoms the actor's objective averages in the update after
    policy step ``step`` (:func:`~bipedal_cli.losses.actor_loss`'s ``lowest``):

        L(t) = max(1, floor(c N M + 1/2))   t > actor_cvar_start, c = agent.actor_cvar
        L(t) = None (all: eq. 2)            t <= actor_cvar_start, or c None
    """
    a = agent_cfg
    if a.actor_cvar is None or step <= a.actor_cvar_start:
        return None
    return max(1, math.floor(a.actor_cvar * a.n_critics * a.n_quantiles + 0.5))


def batch_size_at(step: int, agent_cfg: Any) -> int:
    """Transitions drawn by each update after policy step ``step``:

    B(t) = batch_size          t <= batch_size_start, or batch_size_final None
    B(t) = batch_size_final    t > batch_size_start
    """
    a = agent_cfg
    return _switched(step, a.batch_size_start, a.batch_size, a.batch_size_final)


def updates_at(step: int, train_cfg: Any) -> int:
    """TQC updates made after policy step ``step`` (the update-to-data ratio):

    U(t) = updates_per_step          t <= updates_per_step_start, or updates_per_step_final None
    U(t) = updates_per_step_final    t > updates_per_step_start
    """
    t = train_cfg
    return _switched(step, t.updates_per_step_start, t.updates_per_step, t.updates_per_step_final)


def _switched(step: int, start: int, before: int, after: int | None) -> int:
    """``before`` up to policy step ``start`` (always, when ``after`` is None), then ``after``."""
    return before if after is None or step <= start else after


def actor_frozen(step: int, agent_cfg: Any) -> bool:
    """Whether the update after policy step ``step`` leaves the actor and the temperature as they
    are (only the critics learn): t <= agent.actor_update_start, and never when it is 0."""
    start = agent_cfg.actor_update_start
    return start > 0 and step <= start


def fall_penalty_at(step: int, train_cfg: Any) -> float | None:
    """The fall penalty for an episode that starts at policy step ``step`` (an episode keeps one
    penalty to its end):

        p(t) = fall_penalty                                            t <= start
        p(t) = fall_penalty + (final - fall_penalty) (t - start) / (end - start)  start < t < end
        p(t) = final                                                   t >= end

    None (the env's own -100) when ``train.fall_penalty`` is None."""
    t = train_cfg
    if t.fall_penalty is None:
        return None
    return linear_ramp(
        step,
        t.fall_penalty,
        t.fall_penalty_final,
        t.fall_penalty_ramp_start,
        t.fall_penalty_ramp_end,
    )


def drop_per_critic_at(step: int, agent_cfg: Any) -> int:
    """k(t), the atoms per critic that the targets of the update after policy step ``step``
    drop from the top of the pooled N*M (:func:`~bipedal_cli.losses.truncated_target`):

    k(t) = drop_per_critic          t <= drop_per_critic_start, or drop_per_critic_final None
    k(t) = drop_per_critic_final    t > drop_per_critic_start
    """
    a = agent_cfg
    return _switched(step, a.drop_per_critic_start, a.drop_per_critic, a.drop_per_critic_final)


def target_entropy_at(step: int, agent_cfg: Any, act_dim: int) -> float:
    """H_T(t), the entropy that the temperature's loss (eq. 3) steers the policy to in the update
    after policy step ``step``:

        H_T(t) = H0                                          t <= start
        H_T(t) = H0 + (final - H0) (t - start) / (end - start)  start < t < end
        H_T(t) = final                                       t >= end

    H0 = agent.target_entropy, or -dim(A) when it is None; final None: H0 throughout.
    """
    a = agent_cfg
    first = float(-act_dim) if a.target_entropy is None else float(a.target_entropy)
    return linear_ramp(
        step,
        first,
        a.target_entropy_final,
        a.target_entropy_decay_start,
        a.target_entropy_decay_end,
    )


def actor_smooth_at(step: int, agent_cfg: Any) -> float | None:
    """lambda(t), the weight of the actor's smoothness term in the update after policy step
    ``step``: agent.actor_smooth when t > actor_smooth_start, else None (no term)."""
    a = agent_cfg
    return a.actor_smooth if step > a.actor_smooth_start else None
