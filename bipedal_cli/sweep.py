"""``bipedal sweep``: the paper's Optuna TPE search, every trial an ordinary run directory.

Objective (minimised): the env steps at which a trial passed the 100-episode test that
``--until-solved`` runs. A trial that does not solve within ``--steps-per-trial`` scores
``budget + 1000 - best evaluation``: below every solved trial, ordered by its best periodic
evaluation. After each periodic evaluation the trial's best evaluation so far goes to a median
pruner (rl-zoo reports the latest one), negated so that lower is better there too: a trial is
stopped when the best it has reached trails what the median trial had reached by the same step,
and one low 5-episode evaluation after good ones does not stop it. A trial whose training
diverges (NaN) is pruned and the study goes on.

Workers: every worker runs the same command. The first creates the study and stores its
definition (search space, base config, steps per trial, budget); the others join it and must
agree. The budget caps the study's trials (failed ones aside, since their retries replace them)
across all workers: see :mod:`bipedal_cli.sweep_storage` for the lock that makes it exact.
"""

from __future__ import annotations

import os
import socket
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .config import Config, config_from_dict
from .errors import UserError
from .rundir import lock_run_dir, prepare_new_run_dir
from .sweep_space import base_params, suggest
from .sweep_storage import make_gate, open_storage
from .sweep_trials import fail_dead_local_trials, live_count, retry

SWEEP_ROOT = Path("sweeps")
DEFINITION = "bipedal"  # the study's user attribute holding its definition
UNSOLVED_MARGIN = 1000.0


@dataclass
class SweepSettings:
    study: str
    base: Config
    space: dict[str, dict[str, Any]]
    trials: int
    steps_per_trial: int
    storage: str | None = None
    seed: int = 0
    heartbeat: int = 60
    pruner_startup: int = 3
    sampler_startup: int = 5  # random trials before TPE models the results
    baseline: bool = True  # the study's first trial is the base config, if inside the space
    pruner_warmup: int | None = None  # env steps; None: a third of a trial
    root: Path = SWEEP_ROOT

    @property
    def study_dir(self) -> Path:
        return self.root / self.study

    def definition(self) -> dict[str, Any]:
        return {
            "space": self.space,
            "config": self.base.to_dict(),
            "steps_per_trial": self.steps_per_trial,
            "trials": self.trials,
        }


class TrialFailed(Exception):
    """A trial that cannot run (its parameters make an invalid config): failed, study goes on."""


class SweepInterrupted(Exception):
    def __init__(self, signum: int) -> None:
        super().__init__(f"interrupted by signal {signum}")
        self.signum = signum


@dataclass
class SweepResult:
    study_dir: Path
    ran: list[int] = field(default_factory=list)  # trial numbers this worker ran
    signal: int | None = None


def _describe_difference(have: dict, want: dict) -> str:
    for key in ("space", "config", "steps_per_trial", "trials"):
        if have.get(key) != want.get(key):
            return key.replace("_", " ")
    return "definition"


def create_or_join(settings: SweepSettings, storage, sampler, pruner):
    """The study: created with its definition by the first worker, joined by the others."""
    import optuna

    name, want = settings.study, settings.definition()
    if name not in optuna.study.get_all_study_names(storage):  # joining writes nothing
        try:
            study = optuna.create_study(
                study_name=name,
                storage=storage,
                direction="minimize",
                sampler=sampler,
                pruner=pruner,
            )
            study.set_user_attr(DEFINITION, want)
            baseline = base_params(settings.base, settings.space) if settings.baseline else None
            if baseline is not None:
                study.enqueue_trial(baseline, user_attrs={"baseline": True})
            return study, True
        except optuna.exceptions.DuplicatedStudyError:  # another machine was first
            pass
    study = optuna.load_study(study_name=name, storage=storage, sampler=sampler, pruner=pruner)
    deadline = time.monotonic() + 30
    while DEFINITION not in study.user_attrs:  # its creator is still writing it
        if time.monotonic() > deadline:
            raise UserError(f"--study {name}: exists but was not created by bipedal sweep")
        time.sleep(0.2)
    have = study.user_attrs[DEFINITION]
    if have != want:
        raise UserError(
            f"--study {name}: already exists with another {_describe_difference(have, want)}; "
            "run the same command as its other workers, or choose another --study"
        )
    return study, False


def trial_config(settings: SweepSettings, params: dict[str, Any]) -> Config:
    data = settings.base.to_dict()
    for key, value in params.items():
        node = data
        *sections, name = key.split(".")
        for part in sections:
            node = node[part]
        node[name] = value
    data["train"]["total_steps"] = settings.steps_per_trial
    try:
        return config_from_dict(data, "sweep trial")
    except UserError as exc:
        raise TrialFailed(str(exc)) from None


def objective(trial, settings: SweepSettings, make_reporter: Callable[[int], Any]) -> float:
    """Train one trial in ``<study dir>/trial-NNNN`` and return its score (see module doc)."""
    import optuna

    from .train import Trainer

    params = suggest(trial, settings.space)
    trial.set_user_attr("worker", f"{socket.gethostname()}:{os.getpid()}")
    cfg = trial_config(settings, params)
    trial.set_user_attr("config", cfg.to_dict())
    run_dir = prepare_new_run_dir(settings.study_dir / f"trial-{trial.number:04d}")
    evals: list[float] = []
    warmup = settings.pruner_warmup
    warmup = settings.steps_per_trial // 3 if warmup is None else warmup

    def report(trainer: Trainer) -> bool:
        mean = float(trainer.last_eval["mean"])
        evals.append(mean)
        trial.report(-max(evals), trainer.step)  # the best so far: one noisy dip never prunes
        return trainer.step >= warmup and trial.should_prune()

    with lock_run_dir(run_dir):
        trainer = Trainer(cfg, run_dir, make_reporter(trial.number))
        trainer.on_evaluation = report
        try:
            result = trainer.run(until_solved=True)
        except UserError as exc:
            if "diverged" in str(exc):
                trial.set_user_attr("diverged", str(exc))
                raise optuna.TrialPruned(str(exc)) from None
            raise
    trial.set_user_attr("env_steps", trainer.env_steps)
    trial.set_user_attr("best_eval", max(evals) if evals else None)
    if trainer.full_eval is not None:
        trial.set_user_attr("test", float(trainer.full_eval["mean"]))
    if result.stopped == "interrupted":
        raise SweepInterrupted(result.signal or 2)
    if result.stopped == "pruned":
        raise optuna.TrialPruned(f"evaluation {evals[-1]:.1f} at step {trainer.step}")
    solved = result.stopped == "solved"
    trial.set_user_attr("solved", solved)
    if solved:
        return float(trainer.env_steps)
    budget = settings.steps_per_trial * cfg.agent.action_repeat
    return budget + UNSOLVED_MARGIN - (max(evals) if evals else -UNSOLVED_MARGIN)


def run_worker(
    settings: SweepSettings,
    make_reporter: Callable[[int], Any],
    on_trial_start: Callable[[Any], None] | None = None,
) -> SweepResult:
    """Join (or create) the study and run trials until the study-wide budget is spent."""
    import optuna

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    warnings.filterwarnings("ignore", category=optuna.exceptions.ExperimentalWarning)
    storage = open_storage(settings.storage, settings.study_dir, settings.heartbeat)
    gate = make_gate(settings.storage, settings.study, settings.study_dir)
    sampler_seed = settings.seed
    gate.acquire()  # creation and the definition check, one worker at a time
    try:
        startup = settings.sampler_startup
        sampler = optuna.samplers.TPESampler(seed=sampler_seed, n_startup_trials=startup)
        pruner = optuna.pruners.MedianPruner(n_startup_trials=settings.pruner_startup)
        study, created = create_or_join(settings, storage, sampler, pruner)
        if not created:  # two workers with one seed would draw the same first parameters
            seed = (sampler_seed + os.getpid()) % 2**31
            study.sampler = optuna.samplers.TPESampler(seed=seed, n_startup_trials=startup)
    finally:
        gate.release()
    result = SweepResult(settings.study_dir)
    while True:
        gate.acquire()
        try:
            optuna.storages.fail_stale_trials(study)
            fail_dead_local_trials(study)
            live, waiting = live_count(study)
            if live >= settings.trials and not waiting:
                break
        except BaseException:
            gate.release()
            raise
        if on_trial_start is not None:
            on_trial_start(study)
        ran: list[int] = []

        def func(trial, ran=ran):
            gate.release()  # the trial exists: the next worker may count and ask
            ran.append(trial.number)
            return objective(trial, settings, make_reporter)

        try:
            study.optimize(func, n_trials=1, catch=(TrialFailed,), gc_after_trial=False)
        except SweepInterrupted as exc:
            retry(study, study.trials[ran[-1]])
            result.ran += ran
            result.signal = exc.signum
            return result
        finally:
            gate.release()
        result.ran += ran
    gate.release()
    return result
