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
from .train import Reporter, Trainer


def load_trainer(
    path: str | Path, reporter: Reporter | None = None, device: str | None = None
) -> Trainer:
    """A Trainer restored from ``path`` (a run directory or its ``state.pt``), ready to run."""
    path = Path(path)
    state_path = path / STATE_FILE if path.is_dir() else path
    if path.is_dir() and not state_path.exists():
        raise UserError(f"RUN_DIR {path}: holds no {STATE_FILE}; nothing to resume")
    state = load_checkpoint(state_path, "RUN_DIR_OR_CHECKPOINT")
    if state["format"] != TRAIN_FORMAT:
        raise UserError(
            f"RUN_DIR_OR_CHECKPOINT {state_path}: a policy-only checkpoint cannot be resumed; "
            f"expected the run's {STATE_FILE}"
        )
    cfg = config_from_dict(state["config"], f"{state_path}: config")
    if device:
        cfg.device = device
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
):
    """Continue the run at ``path``; a curriculum run continues inside its current stage.

    Returns a :class:`~bipedal_cli.train.TrainResult`, or a ``CurriculumResult`` for a
    curriculum run.
    """
    trainer = load_trainer(path, reporter, device)
    if trainer.curriculum is not None:
        if total_steps is not None:
            raise UserError(
                "--steps: a curriculum run takes its budgets from its config "
                "(curriculum.walker_steps, curriculum.hardcore_steps)"
            )
        return continue_curriculum(trainer)
    return trainer.run(total_steps=total_steps, until_solved=until_solved)
