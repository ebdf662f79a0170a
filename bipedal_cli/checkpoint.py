"""Checkpoint files: one training-state file for exact resume, one small policy file.

Both are ``torch.save`` dicts holding only tensors and plain Python values (loaded with
``weights_only=True``), tagged with ``format`` and ``version``. Writes are atomic: the data goes to
a temporary file in the same directory, is fsynced, then renamed over the old file, so a crash or
kill at any moment leaves the previous checkpoint intact.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import torch

from .errors import UserError
from .paths import atomic_path

FORMAT_VERSION = 1
TRAIN_FORMAT = "bipedal-train-state"
POLICY_FORMAT = "bipedal-policy"
STATE_FILE = "state.pt"
POLICY_FILE = "policy.pt"
RESTART_FILE = "restart.pt"  # state.pt without the replay buffer, to commit (run_state.py)
POLICIES_DIR = "policies"  # train.keep_policies: the policy of every periodic evaluation
BEST_POLICY_FILE = "best_policy.pt"  # the policy at the best periodic evaluation of its env


def atomic_save(obj: Any, path: str | Path) -> None:
    """torch.save to ``path`` through a temporary file, fsync and ``os.replace``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with _write_errors(path), atomic_path(path) as tmp, open(tmp, "wb") as f:
        torch.save(obj, f)
        f.flush()
        os.fsync(f.fileno())


@contextmanager
def _write_errors(path: Path) -> Iterator[None]:
    """A failed write (a full disk: ``OSError`` or torch's ``RuntimeError``) as one line naming
    the file; the file itself is untouched, since the data went to a temporary file."""
    try:
        yield
    except (OSError, RuntimeError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else "write failed"
        if isinstance(exc, RuntimeError) and "No space" not in str(exc):
            reason = f"write failed: {str(exc).splitlines()[0][:80]}"
        raise UserError(
            f"{path}: could not be written ({reason}); the previous version is intact"
        ) from None


def load_checkpoint(path: str | Path, option: str = "CKPT") -> dict[str, Any]:
    """Load a policy or training-state file; every failure is a one-line :class:`UserError`."""
    path = Path(path)
    if path.is_dir():
        for name in (STATE_FILE, POLICY_FILE):
            if (path / name).is_file():
                return load_checkpoint(path / name, option)
        raise UserError(f"{option} {path}: directory holds no {STATE_FILE} or {POLICY_FILE}")
    if not path.is_file():
        raise UserError(f"{option} {path}: no such file")
    try:
        data = torch.load(path, map_location="cpu", weights_only=True)
    except Exception:
        raise UserError(
            f"{option} {path}: not a readable bipedal checkpoint (truncated, corrupted or another "
            "format); expected a file written by `bipedal train`"
        ) from None
    if not isinstance(data, dict) or data.get("format") not in (TRAIN_FORMAT, POLICY_FORMAT):
        raise UserError(
            f"{option} {path}: not a bipedal checkpoint; expected a policy.pt or state.pt "
            "written by `bipedal train`"
        )
    version = data.get("version")
    if not isinstance(version, int) or isinstance(version, bool) or version < 1:
        raise UserError(f"{option} {path}: format version {version!r}; expected a positive integer")
    if version > FORMAT_VERSION:
        raise UserError(
            f"{option} {path}: checkpoint format version {version} is newer than "
            f"this bipedal supports ({FORMAT_VERSION}); upgrade bipedal"
        )
    from .schema import check_checkpoint

    check_checkpoint(data, f"{option} {path}", data["format"] == TRAIN_FORMAT)
    data["path"] = str(path)
    return data


def recorded_evaluation(path: Path, env_id: str) -> float | None:
    """The periodic-evaluation mean that the policy file at ``path`` records, or None when there
    is no such file, it cannot be read, or it is a policy of another env (a curriculum's
    earlier stage): the score a new best policy must beat."""
    if not path.is_file():
        return None
    try:
        meta = load_checkpoint(path)["meta"]
        last = meta["last_eval"] if meta["env"] == env_id else None
        return float(last["mean"]) if last else None
    except (UserError, KeyError, TypeError, ValueError):
        return None


def policy_step(path: Path) -> int:
    """The policy step at which the policy file at ``path`` was saved."""
    return int(load_checkpoint(path)["meta"]["steps"])


def actor_weights(data: dict[str, Any]) -> dict[str, torch.Tensor]:
    """The actor's tensors of a checked policy file or training state."""
    return data["actor"] if data["format"] == POLICY_FORMAT else data["agent"]["actor"]


def actor_from_checkpoint(data: dict[str, Any], option: str = "CKPT"):
    """Build the deterministic actor a policy or training-state checkpoint holds (on CPU)."""
    from .config import config_from_dict
    from .networks import make_actor

    cfg = config_from_dict(data["config"], f"{option} {data.get('path', '')}: config".strip())
    actor = make_actor(cfg.agent, int(data["obs_dim"]), int(data["act_dim"]))
    try:
        actor.load_state_dict(actor_weights(data))
    except RuntimeError:
        raise UserError(
            f"{option} {data.get('path')}: actor weights do not match its own config"
        ) from None
    actor.eval()
    return actor, cfg


def check_dims(data: dict[str, Any], obs_dim: int, act_dim: int, env_id: str, option="CKPT"):
    if (int(data["obs_dim"]), int(data["act_dim"])) != (obs_dim, act_dim):
        raise UserError(
            f"{option} {data.get('path')}: policy is for observations of size {data['obs_dim']} "
            f"and actions of size {data['act_dim']}; {env_id} has {obs_dim} and {act_dim}"
        )


# the agent keys that make two actors the same function of the same inputs
POLICY_SHAPE_KEYS = (
    "action_repeat",
    "history",
    "encoder",
    "encoder_hidden",
    "actor_hidden",
    "n_layers",
    "d2rl",
    "log_std_min",
    "log_std_max",
)


def initial_actor_state(cfg: Any, obs_dim: int, act_dim: int) -> dict[str, torch.Tensor]:
    """The actor weights a new run starts from, ``train.init_policy``'s: a policy file (or a
    ``state.pt``) whose bytes match ``train.init_policy_sha256`` when that is set
    (:func:`matching_actor_state`)."""
    t = cfg.train
    return matching_actor_state(
        t.init_policy, "train.init_policy", cfg, obs_dim, act_dim, t.init_policy_sha256
    )


def matching_actor_state(
    path: str | Path,
    option: str,
    cfg: Any,
    obs_dim: int,
    act_dim: int,
    sha256: str | None = None,
) -> dict[str, torch.Tensor]:
    """The actor weights of the policy file (or ``state.pt``) at ``path``, named ``option`` in
    errors: its bytes must match ``sha256`` when that is given, its observation and action sizes
    ``obs_dim`` and ``act_dim``, and its actor this config's shape and inputs
    (:data:`POLICY_SHAPE_KEYS`). Every mismatch is one line naming the file."""
    path = Path(path)
    data = load_checkpoint(path, option)  # a readable, well-formed checkpoint first
    if sha256 is not None:
        got = hashlib.sha256(Path(data["path"]).read_bytes()).hexdigest()
        if got != sha256:
            raise UserError(
                f"{option} {path}: its sha256 is {got}, {option}_sha256 expects {sha256}"
            )
    from .config import config_from_dict

    theirs = config_from_dict(data["config"], f"{option} {path}: config").agent  # all keys
    for key in POLICY_SHAPE_KEYS:
        if getattr(theirs, key) != getattr(cfg.agent, key):
            raise UserError(
                f"{option} {path}: its agent.{key} is {getattr(theirs, key)!r}, this config's is "
                f"{getattr(cfg.agent, key)!r}; expected a policy of the same shape and inputs"
            )
    check_dims(data, obs_dim, act_dim, cfg.env, option)
    return actor_weights(data)


def atomic_write_text(path: str | Path, text: str) -> None:
    """Write a text file (JSON reports) through a temporary file and ``os.replace``."""
    with _write_errors(Path(path)), atomic_path(path) as tmp:
        Path(tmp).write_text(text)
