"""Filling a tree of dataclasses from plain data (parsed YAML), checking each value's type.

A key the dataclass does not have, or a value of the wrong type, raises a one-line
:class:`~bipedal_cli.errors.UserError` that names the key and the file (``source``).
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from typing import Any

from .errors import UserError


def _type_name(tp: Any) -> str:
    if isinstance(tp, type):
        return tp.__name__
    return str(tp).replace("typing.", "")


def _coerce(value: Any, tp: Any, key: str, source: str) -> Any:
    """Check ``value`` against the annotated type ``tp``; ints are accepted for floats."""
    if isinstance(value, float) and not math.isfinite(value):
        raise UserError(f"{source}: key {key!r} expects a finite number, got {value!r}")
    origin = typing.get_origin(tp)
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if value is None and type(None) in args:
            return None
        for arg in args:
            if arg is type(None):
                continue
            try:
                return _coerce(value, arg, key, source)
            except UserError:
                pass
        raise UserError(f"{source}: key {key!r} expects {_type_name(tp)}, got {value!r}")
    if origin is list:
        (item,) = typing.get_args(tp)
        if isinstance(value, list):
            return [_coerce(v, item, f"{key}[{i}]", source) for i, v in enumerate(value)]
    elif tp is bool:
        if isinstance(value, bool):
            return value
    elif tp is int:
        if isinstance(value, int) and not isinstance(value, bool):
            return value
        if isinstance(value, float) and value.is_integer():
            return int(value)
    elif tp is float:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
    elif tp is str:
        if isinstance(value, str):
            return value
    raise UserError(f"{source}: key {key!r} expects {_type_name(tp)}, got {value!r}")


def _fill(obj: Any, data: dict[str, Any], prefix: str, source: str) -> None:
    if not isinstance(data, dict):
        raise UserError(
            f"{source}: section {prefix.rstrip('.') or 'top level'!r} must be a mapping"
        )
    hints = typing.get_type_hints(type(obj))
    names = {f.name for f in dataclasses.fields(obj)}
    for key, value in data.items():
        full = f"{prefix}{key}"
        if key not in names:
            raise UserError(f"{source}: unknown key {full!r}; expected one of {sorted(names)}")
        current = getattr(obj, key)
        if dataclasses.is_dataclass(current):
            _fill(current, value, f"{full}.", source)
        else:
            setattr(obj, key, _coerce(value, hints[key], full, source))


def fill_dataclass(obj: Any, data: Any, source: str) -> None:
    """Set ``obj``'s fields (nested dataclasses too) from the mapping ``data``, in place."""
    _fill(obj, data, "", source)
