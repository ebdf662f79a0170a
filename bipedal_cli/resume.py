"""``bipedal resume``: rebuild a Trainer from a run's ``state.pt`` and continue it.

A curriculum run continues inside its current stage (:mod:`bipedal_cli.curriculum`); this module
sits above both so that neither imports the other's caller.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from .branch_rules import check_branch_config
from .checkpoint import (
    BEST_POLICY_FILE,
    STATE_FILE,
    TRAIN_FORMAT,
    atomic_write_text,
    load_checkpoint,
    policy_step,
    recorded_evaluation,
)
from .config import Config, config_from_dict, override_config
from .curriculum import continue_curriculum
from .errors import UserError
from .metrics import (
    METRICS_FILE,
    MetricsWriter,
    parse_metrics,
    read_metrics,
    restart_metrics_text,
)
from .paths import atomic_path, printable
from .refill import checked_refill_actors
from .reporting import Reporter
from .rundir import BRANCH_FILE, lock_run_dir, prepare_new_run_dir
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


def load_training_state(path: str | Path, restart_ok: bool = False) -> tuple[Path, dict]:
    """``state.pt`` of ``path`` (a run directory or the file), refused when policy-only, and
    a ``restart.pt`` (no replay buffer) unless ``restart_ok``: it continues in a new directory."""
    state_path = state_path_of(path)
    state = load_checkpoint(state_path, "RUN_DIR_OR_CHECKPOINT")
    if state["format"] != TRAIN_FORMAT:
        raise UserError(
            f"RUN_DIR_OR_CHECKPOINT {state_path}: a policy-only checkpoint cannot be resumed; "
            f"expected the run's {STATE_FILE}"
        )
    if state.get("restart") is not None and not restart_ok:
        raise UserError(
            f"RUN_DIR_OR_CHECKPOINT {state_path}: a restart file (no replay buffer) continues "
            f"in a new run directory: bipedal resume {printable(state_path)} --into DIR"
        )
    return state_path, state


def check_budget(total_steps: int, step: int, option: str) -> None:
    """A resumed or branched run's budget is its new total of policy steps: at least its step."""
    if total_steps < step:
        raise UserError(
            f"{option} {total_steps}: the run is at step {step:,}; expected the new total, at "
            "least that"
        )


def load_trainer(
    path: str | Path,
    reporter: Reporter | None = None,
    device: str | None = None,
    total_steps: int | None = None,
    threads: int | None = None,
    keep_policies: bool | None = None,
) -> Trainer:
    """A Trainer restored from ``path`` (a run directory or its ``state.pt``), ready to run;
    ``total_steps`` (the new budget) is checked against the run's step before anything is
    written, ``threads`` and ``keep_policies`` replace ``train.threads`` and
    ``train.keep_policies`` (neither changes the run's bits)."""
    state_path, state = load_training_state(path)
    step = int(state["counters"]["step"])
    if total_steps is not None:
        check_budget(total_steps, step, "--steps")
    data = dict(state["config"])
    if device:
        data["device"] = device
    train_keys = {"threads": threads, "keep_policies": keep_policies}
    options = {k: v for k, v in train_keys.items() if v is not None}
    data["train"] = {**data.get("train", {}), **options}
    source = f"{state_path}: config" + "".join(f" + --{k.replace('_', '-')}" for k in options)
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
    keep_policies: bool | None = None,
):
    """Continue the run at ``path``: a :class:`~bipedal_cli.train.TrainResult`, or for a
    curriculum run (which continues inside its current stage) a ``CurriculumResult``."""
    run_dir = state_path_of(path).parent
    with lock_run_dir(run_dir):
        trainer = load_trainer(path, reporter, device, total_steps, threads, keep_policies)
        if trainer.curriculum is not None:
            if total_steps is not None:
                raise UserError(
                    "--steps: a curriculum run takes its budgets from its config "
                    "(curriculum.walker_steps, curriculum.hardcore_steps)"
                )
            return continue_curriculum(trainer)
        return trainer.run(total_steps=total_steps, until_solved=until_solved)


def branch(
    path: str | Path,
    into: str | Path,
    cfg: Config | None = None,
    reporter: Reporter | None = None,
    until_solved: bool = False,
    config_source: str = "--config",
    overrides: list[str] | None = None,
    explicit: dict | None = None,
):
    """Continue the run at ``path`` in a new directory ``into`` under ``cfg`` (default: the
    run's config with ``overrides``, ``--set`` texts, then ``explicit`` dotted keys).

    ``cfg`` may differ from the run's config only by features that start at or after the run's
    step (a learning-rate decay, replay curation), by the buffer's size while it has never
    wrapped, and by device, threads, budget and kept policies
    (:func:`~bipedal_cli.branch_rules.check_branch_config`): the branch is then, to the bit, the
    run that ``cfg`` trains from scratch, so two recipes can be compared from one shared start.
    The source is only read; ``into`` gets the source's metrics up to the branch step and its
    best policy.

    ``path`` may also be a ``restart.pt`` (:func:`~bipedal_cli.run_state.restart_state`), and
    ``cfg`` and ``overrides`` may then be left out: the run goes on from the file's step in
    ``into`` with the metrics the file holds, and first refills its replay buffer, acting for
    ``train.refill_steps`` policy steps without updates."""
    state_path, state = load_training_state(path, restart_ok=True)
    restart = state.get("restart")
    step = int(state["counters"]["step"])
    if state.get("curriculum") is not None:
        raise UserError(f"RUN_DIR_OR_CHECKPOINT {state_path}: a curriculum run cannot be branched")
    if restart is None and cfg is None and not overrides:
        raise UserError("--into: a branch needs --config FILE or --set key=value to change")
    run_cfg = config_from_dict(state["config"], f"{state_path}: config")
    if cfg is None:
        config_source = f"{state_path}: config + --set"
        cfg = override_config(state["config"], config_source, overrides, **(explicit or {}))
    check_branch_config(run_cfg, cfg, step, config_source, state["buffer"])
    check_budget(cfg.train.total_steps, step, "--steps (train.total_steps)")
    refill_actors = checked_refill_actors(cfg) if restart is not None else None
    into = prepare_new_run_dir(into, "--into")
    with lock_run_dir(into):
        trainer = Trainer(cfg, into, reporter)
        trainer.load_state_dict(state)
        if restart is not None:
            trainer.refill_until = step + cfg.train.refill_steps
            trainer.refill_actors = [actor.to(trainer.device) for actor in refill_actors]
            rows = parse_metrics(restart_metrics_text(restart))
            origin = f"restart file {state_path.resolve()} at step {step}"
        else:
            source_metrics = state_path.parent / METRICS_FILE
            rows = read_metrics(source_metrics) if source_metrics.exists() else None
            _copy_best_policy(state_path.parent / BEST_POLICY_FILE, into, cfg.env, step)
            origin = f"{state_path.resolve()} at step {step}"
        if rows is not None:
            rows = [r for r in rows if int(float(r["step"])) <= step]
            MetricsWriter(into / METRICS_FILE).replace_rows(rows)
        atomic_write_text(into / BRANCH_FILE, f"{origin}\n")
        return trainer.run(until_solved=until_solved)


def _copy_best_policy(best: Path, into: Path, env_id: str, step: int) -> None:
    if recorded_evaluation(best, env_id) is not None and policy_step(best) <= step:
        with atomic_path(into / BEST_POLICY_FILE) as tmp:
            shutil.copyfile(best, tmp)
