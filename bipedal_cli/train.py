"""A training run: its trainer (agent, buffer, env, counters, generators) and its lifecycle;
the loop itself (warm-up, TQC updates, evaluations, checkpoints) is
:mod:`bipedal_cli.training_loop`.

A run lives in one directory (:mod:`bipedal_cli.rundir`): ``config.yaml``, ``metrics.csv``,
``state.pt`` (everything an exact resume needs), ``restart.pt`` (the same without the replay
buffer: small enough to commit) and ``policy.pt`` (the actor alone).

Exact resume (:mod:`bipedal_cli.run_state`): every source of randomness is checkpointed, and an
episode cut by a checkpoint is rebuilt by replaying it. Periodic evaluations, best and kept
policies and the 100-episode test: :mod:`bipedal_cli.periodic_eval`.

``step`` counts policy steps: transitions stored (replay curation may drop some), and updates.
With ``agent.action_repeat`` = k each is k env steps (fewer at an episode's end); ``env_steps``
counts those.
"""

from __future__ import annotations

import signal
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch

from .agent import TQCAgent
from .anchor import anchored
from .buffer import ReplayBuffer
from .checkpoint import STATE_FILE, atomic_save, initial_actor_state
from .config import Config
from .devices import configure_threads, resolve_device
from .envs import policy_dims
from .episode_record import start_episode
from .episodes import EpisodeRunner
from .fall_restarts import FallMemory
from .metrics import METRICS_FILE, MetricsWriter
from .periodic_eval import evaluate_on_eval_seeds
from .reporting import NullReporter, Reporter
from .run_state import policy_file, restore_run_state, run_state, save_run
from .rundir import (
    default_run_dir,
    lock_run_dir,
    prepare_new_run_dir,
    remove_stale_temporaries,
    write_config,
    write_plot,
)
from .schedule import batch_size_at
from .signals import stop_on_signals
from .snapshot import training_snapshot
from .training_loop import train_until


@dataclass
class TrainResult:
    run_dir: Path
    steps: int
    episodes: int
    wall_time: float
    stopped: str  # "budget" | "solved" | "interrupted" | "pruned"
    last_eval: dict | None
    full_eval: dict | None
    signal: int | None = None  # the signal that interrupted it
    env_steps: int | None = None  # env steps (steps counts policy steps)


class Trainer:
    """Owns a run: agent, buffer, env, counters and RNGs; :meth:`run` advances it."""

    def __init__(self, cfg: Config, run_dir: str | Path, reporter: Reporter | None = None):
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        self.reporter = reporter or NullReporter()
        self.device = resolve_device(cfg.device)
        split = configure_threads(cfg.train, self.device)
        torch.manual_seed(cfg.seed)
        self.obs_dim, self.act_dim = policy_dims(cfg.env, cfg.agent)
        self.agent = TQCAgent(cfg.agent, self.obs_dim, self.act_dim, self.device)
        if split:
            self.agent.start_worker(cfg.train.flush_denormal)
        self.agent.noise.manual_seed(cfg.seed + 1)
        self.buffer = ReplayBuffer(
            cfg.train.buffer_size, self.obs_dim, self.act_dim, with_discount=cfg.agent.n_step > 1
        )
        self.runner = EpisodeRunner(cfg, self.buffer)
        self.fall_memory = FallMemory(cfg.train.fall_restart_memory)  # train.fall_restart
        self.rng = np.random.default_rng(cfg.seed)
        self.step = 0  # policy steps
        self.env_steps = 0
        self.refill_until = 0  # a restart from a restart.pt: no updates up to this policy step
        self.refill_actors: list | None = None  # train.refill_policies' (refill.py)
        self.episodes = 0
        self.wall_time = 0.0
        self.recent_returns: deque[float] = deque(maxlen=100)
        self.recent_falls: deque[bool] = deque(maxlen=100)
        self.last_eval: dict | None = None
        self.full_eval: dict | None = None
        self.last_metrics: dict[str, float] = {}
        self.update_metrics: Mapping[str, torch.Tensor] | None = None  # last update's, unsynced
        self.curriculum: dict[str, Any] | None = None  # set by curriculum.py
        self.stop_signal: int | None = None  # set by request_stop
        # called after each periodic evaluation (and full test); True stops the run as
        # "pruned" (bipedal sweep's pruner)
        self.on_evaluation: Callable[[Trainer], bool] | None = None

    # ----------------------------------------------------------------- state
    def state_dict(self) -> dict[str, Any]:
        return run_state(self)

    def load_state_dict(self, state: dict[str, Any]) -> None:
        restore_run_state(self, state)

    def save(self) -> None:
        """state.pt, restart.pt and policy.pt (:func:`~bipedal_cli.run_state.save_run`)."""
        save_run(self)

    def save_policy(self, path: Path) -> None:
        atomic_save(policy_file(self), path)

    def evaluate(self, episodes: int) -> dict:
        """``episodes`` deterministic episodes on the periodic evaluations' seeds."""
        return evaluate_on_eval_seeds(self, episodes)

    # ------------------------------------------------------------------ loop
    def request_stop(self, signum: int = signal.SIGINT) -> None:
        """Stop after the current env step, with a checkpoint (the first Ctrl-C or SIGTERM)."""
        self.stop_signal = signum
        name = "Ctrl-C" if signum == signal.SIGINT else signal.Signals(signum).name
        self.reporter.log(f"{name}: saving a checkpoint and stopping (again to abort)")

    def run(self, total_steps: int | None = None, until_solved: bool = False) -> TrainResult:
        """Train until the budget (``total_steps``, or the config's), a stop signal or, with
        ``until_solved``, a passed 100-episode test; checkpoint and return."""
        cfg, t = self.cfg, self.cfg.train
        if total_steps is not None:  # `resume --steps N` moves the budget; the config says so
            t.total_steps = total_steps
        total = t.total_steps
        self.run_dir.mkdir(parents=True, exist_ok=True)
        remove_stale_temporaries(self.run_dir)
        write_config(self.run_dir, cfg)
        if not (self.run_dir / STATE_FILE).exists():
            self.save()  # step 0: a run killed before its first periodic checkpoint resumes
        metrics = MetricsWriter(self.run_dir / METRICS_FILE)
        with stop_on_signals(self.request_stop):
            stopped, steps_per_s = train_until(self, metrics, total, until_solved)
        self.save()
        self.write_plot()
        self.reporter.update(self.snapshot(steps_per_s))
        self.reporter.close()
        return TrainResult(
            self.run_dir,
            self.step,
            self.episodes,
            self.wall_time,
            stopped,
            self.last_eval,
            self.full_eval,
            self.stop_signal if stopped == "interrupted" else None,
            self.env_steps,
        )

    def learning(self) -> bool:
        """Updates run after the warm-up, and after a restart's refill (``refill_until``)."""
        after = max(self.cfg.train.warmup_steps, self.refill_until)
        return self.step > after and len(self.buffer) >= batch_size_at(self.step, self.cfg.agent)

    def write_plot(self) -> Path | None:
        """``learning_curve.png`` in the run directory (skipped before the first episode ends)."""
        return write_plot(self.run_dir) if self.episodes else None

    def start_episode(self) -> None:
        """The next training episode (:func:`~bipedal_cli.episode_record.start_episode`)."""
        start_episode(self)

    def loss_metrics(self) -> dict[str, float]:
        m = self.update_metrics
        if m is None:
            return {}
        self.last_metrics = {
            k: float(m[k]) for k in ("alpha", "critic_loss", "actor_loss", "entropy", "q_mean")
        }
        return self.last_metrics

    def row_counters(self) -> dict[str, Any]:
        return {
            "stage": self.cfg.env,
            "step": self.step,
            "env_steps": self.env_steps,
            "episode": self.episodes,
            "wall_time": round(self.wall_time, 2),
        }

    def snapshot(self, steps_per_s: float) -> dict[str, Any]:
        self.loss_metrics()
        return training_snapshot(self, steps_per_s)


def train(
    cfg: Config,
    run_dir: str | Path | None = None,
    reporter: Reporter | None = None,
    until_solved: bool = False,
) -> TrainResult:
    """Start a new run in ``run_dir`` (default ``runs/<env>-seed<S>-<time>``) and train it."""
    run_dir = prepare_new_run_dir(run_dir or default_run_dir(cfg))
    with lock_run_dir(run_dir):
        prepare_new_run_dir(run_dir)  # again, now that no other process can start one there
        return new_trainer(cfg, run_dir, reporter).run(until_solved=until_solved)


def new_trainer(cfg: Config, run_dir: Path, reporter: Reporter | None = None) -> Trainer:
    """The trainer of a new run; with ``train.init_policy`` its actor starts as that policy's
    (:func:`~bipedal_cli.checkpoint.initial_actor_state`; a resumed run has its own)."""
    trainer = Trainer(cfg, run_dir, reporter)
    if cfg.train.init_policy is not None:
        actor = initial_actor_state(cfg, trainer.obs_dim, trainer.act_dim)
        trainer.agent.actor.load_state_dict(actor)
        if anchored(cfg.agent):
            trainer.agent.set_anchor()
    return trainer
