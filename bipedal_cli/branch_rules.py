"""What a branch may change: ``bipedal resume RUN --into DIR --config NEW`` continues a run
under a new config only where that config trains, from scratch, the same run up to the branch
point (the values themselves are checked by :mod:`bipedal_cli.validation`)."""

from __future__ import annotations

from typing import Any

from .buffer import fits_resized
from .errors import UserError

BRANCH_MAY_CHANGE = (
    "device",
    "train.threads",
    "train.total_steps",
    "train.keep_policies",
    "train.refill_steps",  # read only when a run restarts from a restart.pt
    "train.refill_policies",  # the same
)
BUFFER_SIZE = "train.buffer_size"  # only while the run's buffer has never wrapped
# Features that start at a policy step: (their keys, the key of that step, is-on, its step).
DEFERRED = (
    (
        ("agent.lr_final", "agent.lr_decay_start", "agent.lr_decay_end"),
        "agent.lr_decay_start",
        lambda c: c.agent.lr_final is not None,
        lambda c: c.agent.lr_decay_start,
    ),
    (
        ("train.replay_keep_below", "train.replay_curation_start"),
        "train.replay_curation_start",
        lambda c: c.train.replay_keep_below is not None,
        lambda c: c.train.replay_curation_start,
    ),
    (
        (
            "train.fall_penalty_final",
            "train.fall_penalty_ramp_start",
            "train.fall_penalty_ramp_end",
        ),
        "train.fall_penalty_ramp_start",
        lambda c: c.train.fall_penalty_final is not None,
        lambda c: c.train.fall_penalty_ramp_start,
    ),
    (
        ("agent.actor_cvar", "agent.actor_cvar_start"),
        "agent.actor_cvar_start",
        lambda c: c.agent.actor_cvar is not None,
        lambda c: c.agent.actor_cvar_start,
    ),
    (
        ("agent.batch_size_final", "agent.batch_size_start"),
        "agent.batch_size_start",
        lambda c: c.agent.batch_size_final is not None,
        lambda c: c.agent.batch_size_start,
    ),
    (
        ("train.updates_per_step_final", "train.updates_per_step_start"),
        "train.updates_per_step_start",
        lambda c: c.train.updates_per_step_final is not None,
        lambda c: c.train.updates_per_step_start,
    ),
    (
        (
            "train.fall_restart",
            "train.fall_restart_back",
            "train.fall_restart_back_min",
            "train.fall_restart_horizon",
            "train.fall_restart_memory",
            "train.fall_restart_probe",
            "train.fall_restart_start",
        ),
        "train.fall_restart_start",
        lambda c: c.train.fall_restart > 0,
        lambda c: c.train.fall_restart_start,
    ),
    (
        (
            "train.obstacle_stump",
            "train.obstacle_stairs",
            "train.obstacle_pit",
            "train.obstacle_mix_start",
        ),
        "train.obstacle_mix_start",
        lambda c: c.train.mixes_obstacles(),
        lambda c: c.train.obstacle_mix_start,
    ),
    (
        ("agent.drop_per_critic_final", "agent.drop_per_critic_start"),
        "agent.drop_per_critic_start",
        lambda c: c.agent.drop_per_critic_final is not None,
        lambda c: c.agent.drop_per_critic_start,
    ),
    (
        (
            "agent.target_entropy_final",
            "agent.target_entropy_decay_start",
            "agent.target_entropy_decay_end",
        ),
        "agent.target_entropy_decay_start",
        lambda c: c.agent.target_entropy_final is not None,
        lambda c: c.agent.target_entropy_decay_start,
    ),
    (
        ("agent.actor_smooth", "agent.actor_smooth_sigma", "agent.actor_smooth_start"),
        "agent.actor_smooth_start",
        lambda c: c.agent.actor_smooth is not None,
        lambda c: c.agent.actor_smooth_start,
    ),
    # the anchor pulls nothing while the actor waits: it is still the anchor itself
    (
        ("agent.actor_anchor", "agent.actor_anchor_kl"),
        "agent.actor_update_start",
        lambda c: c.agent.actor_anchor is not None or c.agent.actor_anchor_kl is not None,
        lambda c: c.agent.actor_update_start,
    ),
)


def _flat(data: dict[str, Any], prefix: str = "") -> dict[str, Any]:
    out: dict[str, Any] = {}
    for key, value in data.items():
        if isinstance(value, dict):
            out.update(_flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


def check_branch_config(
    run_cfg: Any, new_cfg: Any, step: int, source: str, buffer: dict | None = None
) -> None:
    """A branch of a run at ``step`` (``bipedal resume RUN --into DIR --config NEW``) must be the
    run that ``new_cfg`` trains from scratch: every key equal to the run's except the device,
    threads, budget and kept policies (they do not change the bits), features that start
    at a policy step (DEFERRED: learning-rate decay, replay curation, fall-penalty ramp,
    risk-averse actor, larger batch, restarts near falls, obstacle mix, more truncation, falling
    target entropy, actor smoothness) as long as they change
    nothing before ``step``, and the replay buffer's size while the run's ``buffer`` (its saved
    state: capacity, size, pos) has never wrapped and fits the new size. One line naming the
    first key that breaks this."""
    old, new = _flat(run_cfg.to_dict()), _flat(new_cfg.to_dict())
    _check_buffer_resize(old, new, buffer, source)
    own_check = {BUFFER_SIZE}  # keys checked above or in the DEFERRED loop
    for keys, start_key, is_on, start in DEFERRED:
        own_check.update(keys)
        if all(old[k] == new[k] for k in keys):
            continue
        if any(is_on(c) and start(c) < step for c in (run_cfg, new_cfg)):
            raise UserError(
                f"{source}: key {start_key!r} expects a step at or after the branch point "
                f"{step:,} (the run up to there must stay as it was)"
            )
    for key, value in new.items():
        if key in BRANCH_MAY_CHANGE or key in own_check or old.get(key) == value:
            continue
        raise UserError(
            f"{source}: key {key!r} is {value!r}, the run's is {old.get(key)!r}; a branch may "
            "change only device, train.threads, train.total_steps, train.keep_policies, "
            "train.refill_steps, train.buffer_size before the buffer wraps, and "
            "features that start at or after the branch point (learning-rate decay, replay "
            "curation, fall-penalty ramp, risk-averse actor, larger batch, restarts near falls, "
            "actor anchor, obstacle mix, more truncation, target-entropy decay, actor smoothness)"
        )


def _check_buffer_resize(old: dict, new: dict, buffer: dict | None, source: str) -> None:
    """A new ``train.buffer_size`` gives the same run only if the run's ring never wrapped and
    its transitions fit the new one (:func:`~bipedal_cli.buffer.fits_resized`)."""
    was, wanted = old[BUFFER_SIZE], new[BUFFER_SIZE]
    if was == wanted:
        return
    if buffer is not None and fits_resized(int(buffer["size"]), int(buffer["pos"]), was, wanted):
        return
    held = (
        f"holds {int(buffer['size']):,} at position {int(buffer['pos']):,}"
        if buffer
        else "is unknown"
    )
    raise UserError(
        f"{source}: key {BUFFER_SIZE!r} is {wanted!r}, the run's is {was!r}; a branch may "
        "change it only while the run's buffer has never wrapped and fits the new size "
        f"(its buffer {held})"
    )
