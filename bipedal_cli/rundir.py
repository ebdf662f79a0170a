"""Run directories: naming a new one, refusing one that already holds a run, writing its config.

A run directory holds ``config.yaml``, ``metrics.csv``, ``state.pt``, ``restart.pt`` (the
state without its replay buffer), ``policy.pt`` and ``learning_curve.png``. Every file in it is
written as a new file renamed over the old one (:func:`bipedal_cli.paths.atomic_path`), never
through an existing file or link.
"""

from __future__ import annotations

import os
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import yaml

from .checkpoint import STATE_FILE, atomic_write_text
from .config import Config
from .errors import UserError
from .metrics import METRICS_FILE

CONFIG_FILE = "config.yaml"
PLOT_FILE = "learning_curve.png"
LOCK_FILE = ".lock"
BRANCH_FILE = "branched_from.txt"  # a branch's source: `<state.pt> at step <N>`


@contextmanager
def lock_run_dir(run_dir: Path) -> Iterator[None]:
    """Hold an exclusive OS lock (``fcntl.flock``) on ``run_dir/.lock`` while inside.

    A second process gets a one-line error naming the directory and the PID that holds it. The
    kernel drops the lock when its process dies (``kill -9``, a reboot), so a stale lock file
    never blocks a later resume.
    """
    import fcntl

    run_dir.mkdir(parents=True, exist_ok=True)
    path = run_dir / LOCK_FILE
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
    except OSError as exc:
        raise UserError(f"{run_dir}: cannot create its lock file {path} ({exc.strerror})") from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
        os.close(fd)
        raise UserError(
            f"{run_dir}: in use by another bipedal process (PID {holder}); wait for it to "
            "finish or stop it (Ctrl-C or kill PID saves a checkpoint)"
        ) from None
    try:
        os.ftruncate(fd, 0)
        os.pwrite(fd, str(os.getpid()).encode(), 0)
        yield
    finally:
        fcntl.flock(fd, fcntl.LOCK_UN)
        os.close(fd)


def remove_stale_temporaries(run_dir: Path) -> list[Path]:
    """Delete ``.state.*.tmp.pt`` and the like: half-written files of a process killed while
    saving (call it with the run's lock held)."""
    stale = [p for p in run_dir.glob(".*.tmp*") if p.is_file() or p.is_symlink()]
    for p in stale:
        p.unlink(missing_ok=True)
    return stale


def prepare_new_run_dir(run_dir: str | Path, option: str = "--run-dir") -> Path:
    """``run_dir`` unless it already holds a run (a ``state.pt``: every run writes one at
    step 0, before its metrics). A directory left by a process killed before that holds at
    most ``config.yaml``: a new run may start there."""
    run_dir = Path(run_dir)
    if (run_dir / STATE_FILE).exists() or (run_dir / METRICS_FILE).exists():
        raise UserError(
            f"{option} {run_dir}: already holds a run; continue it with `bipedal resume "
            f"{run_dir}` or choose another directory"
        )
    if run_dir.exists() and not run_dir.is_dir():
        raise UserError(f"{option} {run_dir}: exists and is not a directory")
    return run_dir


def default_run_dir(cfg: Config, kind: str | None = None, root: str | Path = "runs") -> Path:
    """``runs/<kind>-seed<S>-<time>``; kind defaults to walker or hardcore."""
    kind = kind or ("hardcore" if "Hardcore" in cfg.env else "walker")
    stamp = time.strftime("%Y%m%d-%H%M%S")
    return Path(root) / f"{kind}-seed{cfg.seed}-{stamp}"


def write_config(run_dir: Path, cfg: Config) -> None:
    """The resolved config as ``config.yaml``."""
    atomic_write_text(run_dir / CONFIG_FILE, yaml.safe_dump(cfg.to_dict(), sort_keys=False))


def write_plot(run_dir: Path) -> Path:
    """``learning_curve.png`` of the run's metrics."""
    from .paths import printable
    from .plotting import plot_runs

    return plot_runs([run_dir], run_dir / PLOT_FILE, title=printable(run_dir.name))
