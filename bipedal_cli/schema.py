"""What a checkpoint must hold, checked before anything is built from it.

:func:`check_checkpoint` walks a loaded ``policy.pt`` or ``state.pt`` and raises a one-line
:class:`UserError` at the first key that is missing, of the wrong type or shape, or not finite.
Expected shapes come from the checkpoint's own config, with the networks built on the ``meta``
device (shapes only, no memory), so a file that declares huge sizes fails here, not in an
allocation.
"""

from __future__ import annotations

import math
import zlib
from collections.abc import Mapping
from typing import Any

import torch

from .config import Config, config_from_dict
from .errors import UserError
from .metrics import restart_metrics_text
from .validation import ACT_SIZE, OBS_SIZE

AGENT_NETWORKS = ("actor", "critic", "critic_target")
OPTIMIZERS = {"actor_opt": "actor", "critic_opt": "critic", "alpha_opt": None}


def _fail(where: str, key: str, expected: str) -> UserError:
    return UserError(f"{where}: {key!r} {expected}; the file is not a valid bipedal checkpoint")


def _get(data: Mapping, key: str, kind, where: str, path: str = "") -> Any:
    full = f"{path}{key}"
    if not isinstance(data, Mapping) or key not in data:
        raise _fail(where, full, "is missing")
    value = data[key]
    if kind is not None and not isinstance(value, kind) or isinstance(value, bool) and kind is int:
        raise _fail(where, full, f"should be {getattr(kind, '__name__', kind)}")
    return value


def _shapes(cfg: Config, obs_dim: int, act_dim: int) -> dict[str, dict[str, tuple[int, ...]]]:
    from .networks import make_actor, make_critics

    a = cfg.agent
    with torch.device("meta"):
        actor = make_actor(a, obs_dim, act_dim)
        critic = make_critics(a, obs_dim, act_dim)
    actor_shapes = {k: tuple(v.shape) for k, v in actor.state_dict().items()}
    critic_shapes = {k: tuple(v.shape) for k, v in critic.state_dict().items()}
    return {"actor": actor_shapes, "critic": critic_shapes, "critic_target": critic_shapes}


def _check_weights(
    weights: Any, expected: dict[str, tuple[int, ...]], where: str, key: str, finite=True
) -> None:
    if not isinstance(weights, Mapping) or set(weights) != set(expected):
        raise _fail(where, key, "does not hold the parameters its config describes")
    for name, shape in expected.items():
        t = weights[name]
        if not torch.is_tensor(t) or tuple(t.shape) != shape or not t.is_floating_point():
            got = tuple(t.shape) if torch.is_tensor(t) else type(t).__name__
            raise _fail(where, f"{key}.{name}", f"has shape {got}; its config implies {shape}")
        if finite and not bool(torch.isfinite(t).all()):
            raise _fail(where, f"{key}.{name}", "holds NaN or infinite values")


def check_checkpoint(data: dict, where: str, train_state: bool) -> Config:
    """Check ``data`` (a loaded policy file, or with ``train_state`` a training state) and
    return its config."""
    raw_cfg = _get(data, "config", Mapping, where)
    cfg = config_from_dict(dict(raw_cfg), f"{where}: config")
    env = _get(data, "env", str, where)
    if env != cfg.env:
        raise _fail(where, "env", f"is {env}, its config says {cfg.env}")
    obs_dim, act_dim = _get(data, "obs_dim", int, where), _get(data, "act_dim", int, where)
    want = (cfg.agent.history * OBS_SIZE, ACT_SIZE)
    if (obs_dim, act_dim) != want:
        raise _fail(where, "obs_dim/act_dim", f"are {obs_dim}/{act_dim}; expected {want}")
    shapes = _shapes(cfg, obs_dim, act_dim)
    if not train_state:
        _check_weights(_get(data, "actor", Mapping, where), shapes["actor"], where, "actor")
        _get(data, "meta", Mapping, where)
        return cfg
    agent = _get(data, "agent", Mapping, where)
    for net in AGENT_NETWORKS:
        _check_weights(
            _get(agent, net, Mapping, where, "agent."), shapes[net], where, f"agent.{net}"
        )
    if agent.get("anchor") is not None:  # agent.actor_anchor's initial actor
        _check_weights(agent["anchor"], shapes["actor"], where, "agent.anchor")
    log_alpha = _get(agent, "log_alpha", torch.Tensor, where, "agent.")
    if log_alpha.numel() != 1 or not bool(torch.isfinite(log_alpha).all()):
        raise _fail(where, "agent.log_alpha", "should be one finite number")
    for opt, net in OPTIMIZERS.items():
        _check_optimizer(_get(agent, opt, Mapping, where, "agent."), shapes.get(net), where, opt)
    _get(agent, "noise_rng", torch.Tensor, where, "agent.")
    _get(agent, "updates", int, where, "agent.")
    _check_buffer(_get(data, "buffer", Mapping, where), cfg, obs_dim, act_dim, where)
    counters = _get(data, "counters", Mapping, where)
    for key in ("step", "episodes"):
        if _get(counters, key, int, where, "counters.") < 0:
            raise _fail(where, f"counters.{key}", "should not be negative")
    wall = _get(counters, "wall_time", (int, float), where, "counters.")
    if not math.isfinite(wall):
        raise _fail(where, "counters.wall_time", "should be finite")
    if "refill_until" in counters and _get(counters, "refill_until", int, where, "counters.") < 0:
        raise _fail(where, "counters.refill_until", "should not be negative")
    if data.get("restart") is not None:
        _check_restart(data, where)
    episode = _get(data, "episode", Mapping, where)
    actions = _get(episode, "actions", torch.Tensor, where, "episode.")
    if actions.dim() != 2 or actions.shape[1] != act_dim:
        raise _fail(where, "episode.actions", f"should be (steps, {act_dim})")
    _get(episode, "seed", int, where, "episode.")
    penalty = episode.get("fall_penalty")  # since 2026-11-25; before, the config's throughout
    if penalty is not None and (
        isinstance(penalty, bool)
        or not isinstance(penalty, (int, float))
        or not math.isfinite(penalty)
    ):
        raise _fail(where, "episode.fall_penalty", "should be null or a finite number")
    restart_at = episode.get("restart_at")  # since 2026-12-03: a restart near a fall
    if restart_at is not None and not (
        type(restart_at) is int and 0 <= restart_at <= actions.shape[0]
    ):
        raise _fail(where, "episode.restart_at", f"should be null or in [0, {actions.shape[0]}]")
    for flag in ("probe", "obstacle_mix"):  # since 2026-12-03 and 2026-12-06
        if type(episode.get(flag, False)) is not bool:
            raise _fail(where, f"episode.{flag}", "should be true or false")
    _check_fall_memory(data.get("fall_memory") or [], act_dim, where)
    if data.get("machine") is not None:  # since 2026-12-05: where it was saved
        _get(data, "machine", str, where)
    _get(data, "rng", Mapping, where)
    _get(data, "recent_returns", list, where)
    if "recent_falls" in data:  # since 2026-11-24; older checkpoints start it empty
        _get(data, "recent_falls", list, where)
    return cfg


def _check_fall_memory(falls: Any, act_dim: int, where: str) -> None:
    """``train.fall_restart``'s remembered falls: env seeds and (steps, act_dim) actions."""
    if not isinstance(falls, list):
        raise _fail(where, "fall_memory", "should be a list")
    for i, fall in enumerate(falls):
        seed = _get(fall, "seed", int, where, f"fall_memory.{i}.")
        actions = _get(fall, "actions", torch.Tensor, where, f"fall_memory.{i}.")
        if not 0 <= seed < 2**31:
            raise _fail(where, f"fall_memory.{i}.seed", "should be in [0, 2^31)")
        if actions.dim() != 2 or actions.shape[1] != act_dim or not actions.is_floating_point():
            raise _fail(where, f"fall_memory.{i}.actions", f"should be (steps, {act_dim}) floats")


def _check_restart(data: dict, where: str) -> None:
    """A ``restart.pt``: the step it was written at, the run's metrics, and no replay."""
    restart = _get(data, "restart", Mapping, where)
    if _get(restart, "step", int, where, "restart.") != data["counters"]["step"]:
        raise _fail(where, "restart.step", "should be counters.step")
    if "metrics_csv_zlib" not in restart:
        _get(restart, "metrics_csv", str, where, "restart.")
    elif not isinstance(restart["metrics_csv_zlib"], bytes):
        raise _fail(where, "restart.metrics_csv_zlib", "should be bytes")
    else:
        try:
            restart_metrics_text(restart)
        except (zlib.error, UnicodeDecodeError):
            raise _fail(where, "restart.metrics_csv_zlib", "is not zlib-packed text") from None
    if data["buffer"]["size"] != 0:
        raise _fail(where, "buffer", "should be empty in a restart file")


def _check_optimizer(state: Mapping, shapes: dict | None, where: str, key: str) -> None:
    groups = _get(state, "param_groups", list, where, f"agent.{key}.")
    per_param = _get(state, "state", Mapping, where, f"agent.{key}.")
    expected = list(shapes.values()) if shapes is not None else [()]
    if sum(len(g.get("params", [])) for g in groups if isinstance(g, Mapping)) != len(expected):
        raise _fail(where, f"agent.{key}", "does not match its network's parameters")
    for index, moments in per_param.items():
        if not isinstance(index, int) or not 0 <= index < len(expected):
            raise _fail(where, f"agent.{key}.state", "refers to unknown parameters")
        for name in ("exp_avg", "exp_avg_sq"):
            t = moments.get(name) if isinstance(moments, Mapping) else None
            if not torch.is_tensor(t) or tuple(t.shape) != tuple(expected[index]):
                raise _fail(where, f"agent.{key}.state.{index}.{name}", "has the wrong shape")


def _check_buffer(buf: Mapping, cfg: Config, obs_dim: int, act_dim: int, where: str) -> None:
    size, pos = _get(buf, "size", int, where, "buffer."), _get(buf, "pos", int, where, "buffer.")
    capacity = _get(buf, "capacity", int, where, "buffer.")
    if capacity != cfg.train.buffer_size or not (0 <= size <= capacity and 0 <= pos < capacity):
        raise _fail(where, "buffer", f"size {size}, pos {pos} do not fit capacity {capacity}")
    fields = {"obs": (size, obs_dim), "action": (size, act_dim), "reward": (size,)}
    fields.update({"next_obs": (size, obs_dim), "terminated": (size,)})
    if cfg.agent.n_step > 1:
        fields["discount"] = (size,)
    for name, shape in fields.items():
        t = _get(buf, name, torch.Tensor, where, "buffer.")
        if tuple(t.shape) != shape:
            raise _fail(where, f"buffer.{name}", f"has shape {tuple(t.shape)}; expected {shape}")
