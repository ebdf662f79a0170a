"""Typed configuration: dataclasses with defaults, filled from YAML, overridden by ``--set``.

Precedence, resolved in one place (:func:`resolve_config`): ``--set key=value`` wins over the
YAML file, the YAML file over the dataclass defaults. Unknown keys and wrong types raise
:class:`~bipedal_cli.errors.UserError` naming the key.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .agent_config import AgentConfig
from .config_yaml import load_yaml, parse_override, set_nested
from .env_ids import canonical_env_id
from .train_config import TrainConfig
from .typed_fill import fill_dataclass
from .validation import validate

__all__ = [
    "AgentConfig",
    "Config",
    "CurriculumConfig",
    "TrainConfig",
    "config_from_dict",
    "override_config",
    "resolve_config",
]


@dataclass
class CurriculumConfig:
    """``bipedal curriculum``: BipedalWalker-v3 first, then BipedalWalkerHardcore-v3."""

    walker_steps: int = 300_000
    """Stage 1 budget: env steps on BipedalWalker-v3 (it ends earlier once solved)."""
    hardcore_steps: int = 3_000_000
    """Stage 2 budget: env steps on BipedalWalkerHardcore-v3 (ends earlier once solved)."""
    replay: str = "keep"
    """At the switch: keep the Walker transitions in the replay buffer, or clear it."""


@dataclass
class Config:
    """Everything a run needs; one YAML file fills it."""

    env: str = "BipedalWalker-v3"
    """Gymnasium id (or alias walker / hardcore)."""
    seed: int = 0
    """Seeds networks, exploration, replay sampling and env resets."""
    device: str = "auto"
    """auto, cpu or cuda."""
    agent: AgentConfig = field(default_factory=AgentConfig)
    train: TrainConfig = field(default_factory=TrainConfig)
    curriculum: CurriculumConfig = field(default_factory=CurriculumConfig)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def config_from_dict(data: dict[str, Any], source: str = "config") -> Config:
    cfg = Config()
    fill_dataclass(cfg, data or {}, source)
    cfg.env = canonical_env_id(cfg.env, f"{source}: key 'env'")
    validate(cfg, source)  # the range of every value (validation.py)
    return cfg


def resolve_config(
    config_path: str | Path | None = None,
    overrides: list[str] | None = None,
    **explicit: Any,
) -> Config:
    """YAML file, then ``--set`` overrides, then explicit CLI options that are not None.

    ``explicit`` maps dotted keys (``'train.total_steps'``) to values from dedicated options.
    """
    data: dict[str, Any] = load_yaml(config_path) if config_path else {}
    return override_config(
        data, str(config_path) if config_path else "config", overrides, **explicit
    )


def override_config(
    data: dict[str, Any], source: str, overrides: list[str] | None = None, **explicit: Any
) -> Config:
    """``data`` (a config as a dict, named ``source`` in errors) with ``--set`` overrides, then
    explicit CLI options that are not None, resolved."""
    data = copy.deepcopy(data)
    for text in overrides or []:
        path, value = parse_override(text)
        set_nested(data, path, value)
        source = f"{source} + --set" if "--set" not in source else source
    for dotted, value in explicit.items():
        if value is not None:
            set_nested(data, dotted.split("."), value)
    return config_from_dict(data, source)
