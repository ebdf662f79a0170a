"""The two environments by alias or Gymnasium id, resolved to the full id in one place."""

from __future__ import annotations

from .errors import UserError

ENV_ALIASES = {
    "walker": "BipedalWalker-v3",
    "hardcore": "BipedalWalkerHardcore-v3",
}
KNOWN_ENVS = tuple(ENV_ALIASES.values())


def canonical_env_id(name: str, option: str = "--env") -> str:
    """Map ``walker``/``hardcore`` or a full Gymnasium id to the full id; reject anything else."""
    if name in ENV_ALIASES:
        return ENV_ALIASES[name]
    if name in KNOWN_ENVS:
        return name
    expected = ", ".join([*ENV_ALIASES, *KNOWN_ENVS])
    raise UserError(f"{option}: unknown environment {name!r}; expected one of {expected}")
