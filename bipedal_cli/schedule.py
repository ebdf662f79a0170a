"""The learning-rate schedule: constant, or a linear decay over a window of policy steps.

rl-zoo's tuned TQC for BipedalWalkerHardcore-v3 decays its learning rate linearly over the run;
ours is constant unless ``agent.lr_final`` is set. The schedule is a pure function of the policy
step, so it adds nothing to a checkpoint and a resumed run follows it exactly.
"""

from __future__ import annotations

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
    if final is None or step <= start:
        return lr
    if step >= end:
        return final
    return lr + (final - lr) * (step - start) / (end - start)


def scheduled_learning_rate(step: int, agent_cfg: Any) -> float | None:
    """``learning_rate_at`` for an :class:`~bipedal_cli.config.AgentConfig`; None when its
    schedule is constant (the optimizers keep ``agent.lr`` and are never touched)."""
    if agent_cfg.lr_final is None:
        return None
    return learning_rate_at(
        step, agent_cfg.lr, agent_cfg.lr_final, agent_cfg.lr_decay_start, agent_cfg.lr_decay_end
    )
