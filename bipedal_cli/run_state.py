"""A training run's state, ``state.pt``: what it holds and how a Trainer is put back from it.

Exact resume: every source of randomness is one of three checkpointed generators (numpy for
warm-up actions, episode seeds and replay sampling; a torch generator for exploration noise; the
global torch RNG), and an episode cut by a checkpoint is rebuilt by replaying it
(:mod:`bipedal_cli.episodes`).
"""

from __future__ import annotations

from collections import deque
from typing import Any

import numpy as np
import torch

from .adam_moments import without_moments
from .checkpoint import (
    FORMAT_VERSION,
    POLICY_FILE,
    RESTART_FILE,
    STATE_FILE,
    TRAIN_FORMAT,
    atomic_save,
)
from .checkpoint_contents import policy_payload
from .devices import machine_summary
from .errors import UserError
from .metrics import METRICS_FILE, pack_metrics


def run_state(trainer: Any, replay: bool = True) -> dict[str, Any]:
    """Everything an exact resume needs, the ``state.pt`` of a
    :class:`~bipedal_cli.train.Trainer`; without ``replay``, the replay buffer and the episode
    in progress are left empty (:func:`restart_state`)."""
    buffer = trainer.buffer.state_dict() if replay else empty_buffer_state(trainer.buffer)
    episode = trainer.runner.state_dict(trainer.act_dim)
    if not replay:
        episode = {
            **episode,
            "obs": None,
            "actions": torch.zeros(0, trainer.act_dim),
            "restart_at": None,
        }
    return {
        "format": TRAIN_FORMAT,
        "version": FORMAT_VERSION,
        "config": trainer.cfg.to_dict(),
        "env": trainer.cfg.env,
        "obs_dim": trainer.obs_dim,
        "act_dim": trainer.act_dim,
        "agent": trainer.agent.state_dict(),
        "buffer": {
            k: torch.from_numpy(v) if isinstance(v, np.ndarray) else v for k, v in buffer.items()
        },
        "counters": {
            "step": trainer.step,
            "env_steps": trainer.env_steps,
            "episodes": trainer.episodes,
            "wall_time": trainer.wall_time,
            "refill_until": trainer.refill_until,
        },
        "episode": episode,
        "recent_returns": list(trainer.recent_returns),
        "recent_falls": list(trainer.recent_falls),
        "fall_memory": trainer.fall_memory.state_dict(),  # train.fall_restart
        "rng": {
            "numpy": trainer.rng.bit_generator.state,
            "torch": torch.get_rng_state(),
            "cuda": torch.cuda.get_rng_state_all() if trainer.device.type == "cuda" else None,
        },
        "last_eval": trainer.last_eval,
        "full_eval": trainer.full_eval,
        "curriculum": trainer.curriculum,
        "machine": machine_summary(trainer.device),  # since 2026-12-05
        # so that an episode ending right after a resume still logs its losses
        "update_metrics": (
            None
            if trainer.update_metrics is None
            else {k: float(v) for k, v in trainer.update_metrics.items()}
        ),
    }


def restore_run_state(trainer: Any, state: dict[str, Any]) -> None:
    """Put ``trainer`` where :func:`run_state` left it; an episode cut by the checkpoint is
    rebuilt by replaying its actions from its seed."""
    trainer.agent.load_state_dict(state["agent"])
    buf = {k: v.numpy() if torch.is_tensor(v) else v for k, v in state["buffer"].items()}
    trainer.buffer.load_state_dict(buf)
    c = state["counters"]
    trainer.step, trainer.episodes, trainer.wall_time = (
        int(c["step"]),
        int(c["episodes"]),
        c["wall_time"],
    )
    trainer.env_steps = int(c.get("env_steps", trainer.step))
    trainer.refill_until = int(c.get("refill_until", 0))  # since 2026-12-02
    trainer.recent_returns = deque(state["recent_returns"], maxlen=100)
    trainer.recent_falls = deque(map(bool, state.get("recent_falls", [])), maxlen=100)
    trainer.fall_memory.load_state_dict(state.get("fall_memory"))  # since 2026-12-03
    trainer.rng.bit_generator.state = state["rng"]["numpy"]
    torch.set_rng_state(state["rng"]["torch"])
    if state["rng"].get("cuda") is not None and trainer.device.type == "cuda":
        torch.cuda.set_rng_state_all(state["rng"]["cuda"])
    trainer.last_eval, trainer.full_eval = state["last_eval"], state["full_eval"]
    trainer.curriculum = state.get("curriculum")
    warn_if_other_machine(trainer, state.get("machine"))
    m = state.get("update_metrics")
    trainer.update_metrics = None if m is None else {k: torch.tensor(v) for k, v in m.items()}
    ep = state["episode"]
    if ep["obs"] is not None:
        # checkpoints before the fall-penalty ramp had one penalty: the config's
        penalty = ep["fall_penalty"] if "fall_penalty" in ep else trainer.cfg.train.fall_penalty
        rebuilt = trainer.runner.replay(
            int(ep["seed"]),
            ep["actions"].numpy(),
            ep["obs"].numpy(),
            bool(ep.get("curated")),
            None if penalty is None else float(penalty),
            ep.get("restart_at"),
            bool(ep.get("probe")),  # since 2026-12-03: train.fall_restart_probe
            bool(ep.get("obstacle_mix")),  # since 2026-12-06: train.obstacle_*
        )
        if not rebuilt:
            trainer.reporter.log(
                "warning: the replayed episode differs from the checkpoint's; the resumed "
                "run will not match an uninterrupted one exactly"
            )


def warn_if_other_machine(trainer: Any, saved_on: str | None) -> None:
    """A run resumed on another kind of machine goes on correctly, but its bits part from the
    uninterrupted run's at the first update (different kernels round differently), so
    ``benchmarks/same_run.py`` against it will report a difference: say so once."""
    here = machine_summary(trainer.device)
    if saved_on is not None and saved_on != here:
        trainer.reporter.log(
            f"note: this state was saved on {saved_on}; this is {here}. The run goes on, "
            "but will not match one that stayed on the first machine bit for bit"
        )


def diverged(trainer: Any, what: str) -> UserError:
    saved = trainer.run_dir / STATE_FILE
    return UserError(
        f"training diverged at step {trainer.step:,}: {what} is not finite (NaN or inf); "
        f"{saved} keeps the last good checkpoint"
    )


def save_run(trainer: Any) -> None:
    """``state.pt``, ``restart.pt`` and ``policy.pt`` of a run; refused (the last good ones
    kept) when a network holds NaN."""
    trainer.agent.sync()
    for name in ("actor", "critic"):
        params = getattr(trainer.agent, name).parameters()
        if not all(bool(torch.isfinite(p).all()) for p in params):
            raise diverged(trainer, f"the {name}'s weights")
    run_dir = trainer.run_dir
    atomic_save(run_state(trainer), run_dir / STATE_FILE)
    metrics = run_dir / METRICS_FILE
    metrics_csv = metrics.read_text() if metrics.is_file() else ""
    atomic_save(restart_state(trainer, metrics_csv), run_dir / RESTART_FILE)
    trainer.save_policy(run_dir / POLICY_FILE)


def empty_buffer_state(buffer: Any) -> dict[str, Any]:
    """A replay buffer's state with no transition (its capacity and fields kept)."""
    data = {name: getattr(buffer, name)[:0].copy() for name in buffer.fields}
    return {"capacity": buffer.capacity, "size": 0, "pos": 0, **data}


def restart_state(trainer: Any, metrics_csv: str) -> dict[str, Any]:
    """The ``restart.pt`` of a run: :func:`run_state` without its replay buffer, its episode in
    progress and the actor's and critics' Adam moments (:mod:`bipedal_cli.adam_moments`), plus
    the run's metrics up to here, zlib-packed: about 16 MiB with critics 512 wide (``ls -l
    checkpoints/restarts/*wide*.pt``), against about 0.8 GB for ``state.pt``. It is what a run
    needs to go on after its directory is lost: networks, targets, the temperature and its
    optimizer, counters and every RNG. Continued with ``bipedal resume FILE --into DIR``, the run
    first refills its buffer (``train.refill_steps``) and estimates the moments again: the same
    agent from the same step, not the same run."""
    state = run_state(trainer, replay=False)
    state["agent"] = without_moments(state["agent"])
    state["restart"] = {"step": trainer.step, "metrics_csv_zlib": pack_metrics(metrics_csv)}
    return state


def policy_file(trainer: Any) -> dict[str, Any]:
    """The ``policy.pt`` of a :class:`~bipedal_cli.train.Trainer`: its actor, config and where
    the run stood (``bipedal info`` prints the meta)."""
    meta = {
        "env": trainer.cfg.env,
        "seed": trainer.cfg.seed,
        "steps": trainer.step,
        "env_steps": trainer.env_steps,
        "episodes": trainer.episodes,
        "wall_time": round(trainer.wall_time, 1),
        "last_eval": trainer.last_eval,
        "full_eval": trainer.full_eval,
        "torch": str(torch.__version__),
        "machine": machine_summary(trainer.device),  # since 2026-12-05
    }
    return policy_payload(
        trainer.agent.actor.state_dict(),
        trainer.cfg.to_dict(),
        trainer.obs_dim,
        trainer.act_dim,
        meta,
    )
