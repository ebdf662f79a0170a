"""The search space of ``bipedal sweep``: which config keys vary, over which ranges.

A space maps dotted config keys to distributions, in YAML::

    agent.lr: {type: float, low: 1.0e-4, high: 2.0e-3, log: true}
    agent.batch_size: {type: categorical, choices: [64, 128, 256]}
    agent.n_critics: {type: int, low: 2, high: 6}

The default is Table 1's columns (the paper's Optuna sweep) over ranges around its values.
Every key, type and range is checked here, once, with one-line errors that name it.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from pathlib import Path
from typing import Any

from .config import Config, load_yaml
from .errors import UserError

DEFAULT_SPACE: dict[str, dict[str, Any]] = {
    "agent.gamma": {"type": "float", "low": 0.95, "high": 0.995},
    "agent.lr": {"type": "float", "low": 1.0e-4, "high": 2.0e-3, "log": True},
    "agent.batch_size": {"type": "categorical", "choices": [64, 128, 256]},
    "train.warmup_steps": {"type": "categorical", "choices": [100, 1000, 5000]},
    "agent.tau": {"type": "float", "low": 0.002, "high": 0.05, "log": True},
    "agent.n_critics": {"type": "int", "low": 2, "high": 6},
    "agent.n_quantiles": {"type": "int", "low": 10, "high": 40, "step": 5},
}
KINDS = ("float", "int", "categorical")


def _key_type(key: str, source: str) -> type:
    """The Python type of config key ``section.name`` (float, int, bool or str)."""
    obj: Any = Config()
    parts = key.split(".")
    for i, part in enumerate(parts):
        names = {f.name for f in dataclasses.fields(obj)}
        if part not in names:
            raise UserError(f"{source}: unknown parameter {key!r}; expected a config key")
        if i == len(parts) - 1:
            hint = typing.get_type_hints(type(obj))[part]
            args = [a for a in typing.get_args(hint) if a is not type(None)]
            tp = args[0] if args else hint
            if tp not in (float, int, bool, str):
                raise UserError(f"{source}: parameter {key!r} cannot be searched")
            return tp
        obj = getattr(obj, part)
        if not dataclasses.is_dataclass(obj):
            raise UserError(f"{source}: unknown parameter {key!r}; expected a config key")
    raise UserError(f"{source}: unknown parameter {key!r}")


def _number(value: Any, key: str, what: str, source: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise UserError(f"{source}: parameter {key!r}: {what} must be a finite number")
    return value


def validate_space(space: Any, source: str) -> dict[str, dict[str, Any]]:
    """The space, checked: known numeric keys, known types, low < high, log only above 0."""
    if not isinstance(space, dict) or not space:
        raise UserError(f"{source}: expected a mapping of config keys to distributions")
    checked: dict[str, dict[str, Any]] = {}
    for key, spec in space.items():
        tp = _key_type(str(key), source)
        if not isinstance(spec, dict) or spec.get("type") not in KINDS:
            raise UserError(f"{source}: parameter {key!r}: expected type float, int or categorical")
        kind = spec["type"]
        allowed = {"type", "choices"} if kind == "categorical" else {"type", "low", "high", "log"}
        if kind == "int":
            allowed.add("step")
        extra = set(spec) - allowed
        if extra:
            raise UserError(f"{source}: parameter {key!r}: unknown fields {sorted(extra)}")
        if kind == "categorical":
            choices = spec.get("choices")
            if not isinstance(choices, list) or not choices:
                raise UserError(f"{source}: parameter {key!r}: choices must be a non-empty list")
            for c in choices:
                ok = isinstance(c, tp) and not (tp is not bool and isinstance(c, bool))
                ok = ok or (tp is float and isinstance(c, int) and not isinstance(c, bool))
                if not ok:
                    raise UserError(
                        f"{source}: parameter {key!r}: choice {c!r} is not a {tp.__name__}"
                    )
            checked[key] = {"type": kind, "choices": list(choices)}
            continue
        if tp not in (int, float) or (kind == "float" and tp is int):
            raise UserError(
                f"{source}: parameter {key!r} is a {tp.__name__}; use type {tp.__name__}"
            )
        low = _number(spec.get("low"), key, "low", source)
        high = _number(spec.get("high"), key, "high", source)
        log = spec.get("log", False)
        if not isinstance(log, bool):
            raise UserError(f"{source}: parameter {key!r}: log must be true or false")
        if not low < high or (log and low <= 0):
            raise UserError(
                f"{source}: parameter {key!r}: expected low < high (and low > 0 with log)"
            )
        entry = {"type": kind, "low": low, "high": high, "log": log}
        if kind == "int":
            if not (float(low).is_integer() and float(high).is_integer()):
                raise UserError(f"{source}: parameter {key!r}: int bounds must be integers")
            step = spec.get("step", 1)
            if (
                isinstance(step, bool)
                or not isinstance(step, int)
                or step < 1
                or (log and step != 1)
            ):
                raise UserError(f"{source}: parameter {key!r}: step must be a positive integer")
            entry.update(low=int(low), high=int(high), step=step)
        checked[key] = entry
    return checked


def load_space(path: str | Path | None) -> dict[str, dict[str, Any]]:
    """The space in ``path`` (``--space``), or the default."""
    if path is None:
        return validate_space(DEFAULT_SPACE, "default search space")
    return validate_space(load_yaml(path), f"--space {path}")


def suggest(trial, space: dict[str, dict[str, Any]]) -> dict[str, Any]:
    """Draw one value per key from an Optuna trial: {dotted key: value}."""
    params: dict[str, Any] = {}
    for key, spec in space.items():
        kind = spec["type"]
        if kind == "categorical":
            params[key] = trial.suggest_categorical(key, spec["choices"])
        elif kind == "int":
            step = spec.get("step", 1)
            params[key] = trial.suggest_int(
                key, spec["low"], spec["high"], step=step, log=spec["log"]
            )
        else:
            params[key] = trial.suggest_float(key, spec["low"], spec["high"], log=spec["log"])
    return params


def _within(value: Any, spec: dict[str, Any]) -> bool:
    if spec["type"] == "categorical":
        return value in spec["choices"]
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    if not spec["low"] <= value <= spec["high"]:
        return False
    return spec["type"] != "int" or (value - spec["low"]) % spec.get("step", 1) == 0


def base_params(config: Config, space: dict[str, dict[str, Any]]) -> dict[str, Any] | None:
    """The base config's own value of every searched key, or None if one lies outside the
    space: the baseline trial that a sweep measures first, so its winner is compared with the
    config it started from under the same conditions."""
    data = config.to_dict()
    params: dict[str, Any] = {}
    for key, spec in space.items():
        node: Any = data
        for part in key.split("."):
            node = node[part]
        if not _within(node, spec):
            return None
        params[key] = node
    return params
