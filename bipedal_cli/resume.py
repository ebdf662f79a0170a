"""``bipedal resume``: rebuild a Trainer from a run's ``state.pt`` and continue it.

A curriculum run continues inside its current stage (:mod:`bipedal_cli.curriculum`); this module
sits above both so that neither imports the other's caller.
"""

from __future__ import annotations

from pathlib import Path

from .checkpoint import STATE_FILE, TRAIN_FORMAT, load_checkpoint
from .config import config_from_dict
from .curriculum import continue_curriculum
from .errors import UserError
from .metrics import METRICS_FILE, MetricsWriter
from .reporting import Reporter
from .rundir import lock_run_dir
from .train import Trainer


def state_path_of(path: str | Path) -> Path:
    """``path/state.pt`` for a run directory, ``path`` itself for a file."""
    path = Path(path)
    if not path.is_dir():
        return path
    if not (path / STATE_FILE).exists():
        raise UserError(
            f"RUN_DIR {path}: holds no {STATE_FILE}, so there is nothing to resume (the run "
            f"stopped before it started); start it again with `bipedal train --run-dir {path}`"
        )
    return path / STATE_FILE


def load_trainer(
    path: str | Path,
    reporter: Reporter | None = None,
    device: str | None = None,
    total_steps: int | None = None,
    threads: int | None = None,
) -> Trainer:
    """A Trainer restored from ``path`` (a run directory or its ``state.pt``), ready to run.

    ``total_steps`` (the new budget) is checked against the run's step before anything is
    written; ``threads`` replaces ``train.threads`` (runs are the same bits on 1 or 2 threads).
    """
    state_path = state_path_of(path)
    state = load_checkpoint(state_path, "RUN_DIR_OR_CHECKPOINT")
    if state["format"] != TRAIN_FORMAT:
        raise UserError(
            f"RUN_DIR_OR_CHECKPOINT {state_path}: a policy-only checkpoint cannot be resumed; "
            f"expected the run's {STATE_FILE}"
        )
    step = int(state["counters"]["step"])
    if total_steps is not None and total_steps < step:
        raise UserError(
            f"--steps {total_steps}: the run is at step {step:,}; expected the new total, at "
            "least that"
        )
    data = dict(state["config"])
    if device:
        data["device"] = device
    if threads is not None:
        data["train"] = {**data.get("train", {}), "threads": threads}
    source = f"{state_path}: config" + (" + --threads" if threads is not None else "")
    cfg = config_from_dict(data, source)
    trainer = Trainer(cfg, state_path.parent, reporter)
    trainer.load_state_dict(state)
    metrics_path = state_path.parent / METRICS_FILE
    if metrics_path.exists():
        MetricsWriter(metrics_path).truncate_after(trainer.step)
    return trainer


def resume(
    path: str | Path,
    total_steps: int | None = None,
    reporter: Reporter | None = None,
    until_solved: bool = False,
    device: str | None = None,
    threads: int | None = None,
):
    """Continue the run at ``path``; a curriculum run continues inside its current stage.

    Returns a :class:`~bipedal_cli.train.TrainResult`, or a ``CurriculumResult`` for a
    curriculum run.
    """
    run_dir = state_path_of(path).parent
    with lock_run_dir(run_dir):
        trainer = load_trainer(path, reporter, device, total_steps, threads)
        if trainer.curriculum is not None:
            if total_steps is not None:
                raise UserError(
                    "--steps: a curriculum run takes its budgets from its config "
                    "(curriculum.walker_steps, curriculum.hardcore_steps)"
                )
            return continue_curriculum(trainer)
        return trainer.run(total_steps=total_steps, until_solved=until_solved)
