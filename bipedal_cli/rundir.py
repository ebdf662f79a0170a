"""Run directories: naming a new one, refusing one that already holds a run, writing its config.

A run directory holds ``config.yaml``, ``metrics.csv``, ``state.pt``, ``policy.pt`` and
``learning_curve.png``. Every file in it is written as a new file renamed over the old one
(:func:`bipedal_cli.paths.atomic_path`), never through an existing file or link.
"""

from __future__ import annotations

import time
from pathlib import Path

import yaml

from .checkpoint import STATE_FILE, atomic_write_text
from .config import Config
from .errors import UserError
from .metrics import METRICS_FILE

CONFIG_FILE = "config.yaml"
PLOT_FILE = "learning_curve.png"


def prepare_new_run_dir(run_dir: str | Path, option: str = "--run-dir") -> Path:
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
    from .plotting import plot_runs

    return plot_runs([run_dir], run_dir / PLOT_FILE, title=run_dir.name)
