"""YAML config files and ``--set key=value`` overrides, read into plain dicts that
:func:`bipedal_cli.config.resolve_config` then types and validates."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from .errors import UserError


def load_yaml(path: str | Path) -> dict[str, Any]:
    path = Path(path)
    if not path.is_file():
        raise UserError(f"--config {path}: no such file")
    try:
        data = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        line = getattr(getattr(exc, "problem_mark", None), "line", None)
        where = f" (line {line + 1})" if line is not None else ""
        raise UserError(
            f"{path}: not valid YAML{where}; expected a mapping of config keys"
        ) from None
    except UnicodeDecodeError:
        raise UserError(f"{path}: not a text file; expected a YAML config") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise UserError(f"{path}: expected a mapping of config keys at the top level")
    return data


def parse_override(text: str) -> tuple[list[str], Any]:
    """``'agent.lr=1e-3'`` -> ``(['agent', 'lr'], 0.001)``; values are parsed as YAML scalars."""
    if "=" not in text:
        raise UserError(f"--set {text!r}: expected key=value, e.g. agent.lr=0.0003")
    key, raw = text.split("=", 1)
    try:
        value = yaml.safe_load(raw) if raw.strip() else None
    except yaml.YAMLError:
        value = raw
    if isinstance(value, str) and _looks_numeric(value):
        value = float(value)
    return key.strip().split("."), value


def _looks_numeric(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def set_nested(data: dict[str, Any], path: list[str], value: Any) -> None:
    node = data
    for part in path[:-1]:
        node = node.setdefault(part, {})
        if not isinstance(node, dict):
            raise UserError(f"--set {'.'.join(path)}: {part!r} is not a section")
    node[path[-1]] = value
