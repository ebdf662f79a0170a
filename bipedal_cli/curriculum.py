"""``bipedal curriculum``: BipedalWalker-v3 until solved (or its budget), then Hardcore.

Stage 2 continues with the same networks, optimizers, temperature and RNGs in the same run
directory; ``curriculum.replay`` says whether the Walker transitions stay in the replay buffer
(``keep``, the default: early Hardcore updates still see flat ground) or are dropped (``clear``).
The stage is recorded in the training state, so ``bipedal resume`` continues inside the right
stage, and in ``metrics.csv`` (the ``stage`` column).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .config import Config
from .env_ids import ENV_ALIASES
from .envs import policy_dims
from .errors import UserError
from .reporting import Reporter
from .rundir import default_run_dir, lock_run_dir, prepare_new_run_dir
from .train import Trainer, TrainResult, new_trainer

STAGES = (ENV_ALIASES["walker"], ENV_ALIASES["hardcore"])


@dataclass
class CurriculumResult:
    run_dir: Path
    stages: list[dict[str, Any]]  # per finished stage: env, steps, episodes, wall_time, eval
    stopped: str
    signal: int | None = None  # the signal that interrupted it


def _stage_summary(trainer: Trainer, result: TrainResult, start: dict[str, float]) -> dict:
    return {
        "env": trainer.cfg.env,
        "stopped": result.stopped,
        "steps": result.steps - int(start["step"]),
        "episodes": result.episodes - int(start["episodes"]),
        "wall_time": result.wall_time - start["wall_time"],
        "last_eval": result.last_eval,
        "full_eval": result.full_eval,
    }


def new_curriculum_trainer(
    cfg: Config, run_dir: str | Path | None = None, reporter: Reporter | None = None
) -> Trainer:
    """A trainer in a new run directory, at stage 1 (BipedalWalker-v3) of the curriculum."""
    cfg.env = STAGES[0]
    run_dir = prepare_new_run_dir(run_dir or default_run_dir(cfg, "curriculum"))
    trainer = new_trainer(cfg, run_dir, reporter)
    trainer.curriculum = {"stage": 0, "stage_start": _counters(trainer), "finished": []}
    return trainer


def start_curriculum(
    cfg: Config, run_dir: str | Path | None = None, reporter: Reporter | None = None
) -> CurriculumResult:
    run_dir = prepare_new_run_dir(run_dir or default_run_dir(cfg, "curriculum"))
    with lock_run_dir(run_dir):
        return continue_curriculum(new_curriculum_trainer(cfg, run_dir, reporter))


def switch_env(trainer: Trainer, env_id: str, clear_buffer: bool) -> None:
    """Continue ``trainer`` on another env with the same networks, optimizers and temperature.

    The episode in progress is dropped (it is not counted); evaluations now use ``env_id``.
    """
    trainer.cfg.env = env_id
    dims = policy_dims(env_id, trainer.cfg.agent)
    if dims != (trainer.obs_dim, trainer.act_dim):
        raise UserError(f"{env_id}: observation/action sizes {dims} differ from the agent's")
    if clear_buffer:
        trainer.buffer.size = trainer.buffer.pos = 0
    trainer.last_eval = trainer.full_eval = None
    trainer.recent_returns.clear()
    trainer.recent_falls.clear()
    trainer.fall_memory.falls.clear()  # the previous env's falls: other terrain
    trainer.start_episode()


def _counters(trainer: Trainer) -> dict[str, float]:
    return {"step": trainer.step, "episodes": trainer.episodes, "wall_time": trainer.wall_time}


def continue_curriculum(trainer: Trainer) -> CurriculumResult:
    """Run the remaining stages of a curriculum trainer (new or resumed)."""
    state = trainer.curriculum
    c = trainer.cfg.curriculum
    budgets = (c.walker_steps, c.hardcore_steps)
    stopped = "budget"
    while state["stage"] < len(STAGES):
        stage = state["stage"]
        start = state["stage_start"]
        result = trainer.run(total_steps=int(start["step"]) + budgets[stage], until_solved=True)
        if result.stopped == "interrupted":
            return CurriculumResult(
                trainer.run_dir, list(state["finished"]), "interrupted", result.signal
            )
        state["finished"].append(_stage_summary(trainer, result, start))
        stopped = result.stopped
        state["stage"] = stage + 1
        if state["stage"] < len(STAGES):
            switch_env(trainer, STAGES[state["stage"]], clear_buffer=c.replay == "clear")
            state["stage_start"] = _counters(trainer)
        trainer.save()
    return CurriculumResult(trainer.run_dir, list(state["finished"]), stopped)
