"""The training loop: warm-up, one (or more) TQC updates per env step, evaluation, checkpoints.

A run lives in one directory: ``config.yaml`` (the resolved config), ``metrics.csv``,
``state.pt`` (everything an exact resume needs) and ``policy.pt`` (the actor alone).

Exact resume: every source of randomness is one of three checkpointed generators (numpy for
warm-up actions, episode seeds and replay sampling; a torch generator for exploration noise; the
global torch RNG), and an episode cut by a checkpoint is rebuilt by resetting its env with the
episode's seed and replaying the episode's actions (Box2D is deterministic).
"""

from __future__ import annotations

import os
import signal
import threading
import time
from collections import deque
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

import numpy as np
import torch
import yaml

from .agent import TQCAgent
from .buffer import ReplayBuffer
from .checkpoint import (
    FORMAT_VERSION,
    POLICY_FILE,
    STATE_FILE,
    TRAIN_FORMAT,
    atomic_save,
    load_checkpoint,
    policy_payload,
)
from .config import Config, config_from_dict
from .envs import env_dims, is_fall, make_env
from .errors import UserError
from .evaluation import actor_policy, evaluate_actor, run_episodes, summarize
from .metrics import METRICS_FILE, MetricsWriter

PLOT_FILE = "learning_curve.png"


class Reporter(Protocol):
    """What the loop tells the outside world; the CLI implements it with rich."""

    def start(self, start_step: int, total_steps: int) -> None: ...
    def update(self, snapshot: dict[str, Any]) -> None: ...
    def log(self, text: str) -> None: ...
    def close(self) -> None: ...


class NullReporter:
    def start(self, start_step: int, total_steps: int) -> None:
        pass

    def update(self, snapshot: dict[str, Any]) -> None:
        pass

    def log(self, text: str) -> None:
        pass

    def close(self) -> None:
        pass


def resolve_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if name.startswith("cuda") and not torch.cuda.is_available():
        raise UserError(f"--device {name}: CUDA is not available on this machine; use cpu or auto")
    try:
        return torch.device(name)
    except RuntimeError:
        raise UserError(f"--device {name}: expected auto, cpu or cuda") from None


@dataclass
class EpisodeState:
    """The episode in progress: enough to rebuild the env exactly after a resume."""

    seed: int = 0
    actions: list[np.ndarray] = field(default_factory=list)
    ret: float = 0.0


@dataclass
class TrainResult:
    run_dir: Path
    steps: int
    episodes: int
    wall_time: float
    stopped: str  # "budget" | "solved" | "interrupted"
    last_eval: dict | None
    full_eval: dict | None


class Trainer:
    """Owns a run: agent, buffer, env, counters and RNGs; :meth:`run` advances it."""

    def __init__(self, cfg: Config, run_dir: str | Path, reporter: Reporter | None = None):
        self.cfg = cfg
        self.run_dir = Path(run_dir)
        self.reporter = reporter or NullReporter()
        self.device = resolve_device(cfg.device)
        threads = cfg.train.threads or os.cpu_count() or 1
        split = cfg.train.split_update and self.device.type == "cpu" and threads >= 2
        torch.set_num_threads(threads // 2 if split else threads)  # per part when split
        # process-wide; see TrainConfig.flush_denormal (measured: benchmarks/throughput.py)
        torch.set_flush_denormal(cfg.train.flush_denormal)
        torch.manual_seed(cfg.seed)
        self.env = make_env(cfg.env)
        self.obs_dim, self.act_dim = env_dims(self.env)
        self.agent = TQCAgent(cfg.agent, self.obs_dim, self.act_dim, self.device)
        if split:
            self.agent.start_worker(cfg.train.flush_denormal)
        self.agent.noise.manual_seed(cfg.seed + 1)
        self.buffer = ReplayBuffer(cfg.train.buffer_size, self.obs_dim, self.act_dim)
        self.rng = np.random.default_rng(cfg.seed)
        self.step = 0
        self.episodes = 0
        self.wall_time = 0.0
        self.episode = EpisodeState()
        self.obs: np.ndarray | None = None
        self.recent_returns: deque[float] = deque(maxlen=100)
        self.last_eval: dict | None = None
        self.full_eval: dict | None = None
        self.last_metrics: dict[str, float] = {}
        self._update_metrics: Mapping[str, torch.Tensor] | None = None  # last update's, unsynced
        self.curriculum: dict[str, Any] | None = None  # set by curriculum.py
        self._stop_requested = False

    # ----------------------------------------------------------------- state
    def state_dict(self) -> dict[str, Any]:
        return {
            "format": TRAIN_FORMAT,
            "version": FORMAT_VERSION,
            "config": self.cfg.to_dict(),
            "env": self.cfg.env,
            "obs_dim": self.obs_dim,
            "act_dim": self.act_dim,
            "agent": self.agent.state_dict(),
            "buffer": {
                k: torch.from_numpy(v) if isinstance(v, np.ndarray) else v
                for k, v in self.buffer.state_dict().items()
            },
            "counters": {"step": self.step, "episodes": self.episodes, "wall_time": self.wall_time},
            "episode": {
                "seed": self.episode.seed,
                "actions": torch.from_numpy(
                    np.array(self.episode.actions, np.float32).reshape(-1, self.act_dim)
                ),
                "ret": self.episode.ret,
                "obs": None if self.obs is None else torch.from_numpy(self.obs.copy()),
            },
            "recent_returns": list(self.recent_returns),
            "rng": {
                "numpy": self.rng.bit_generator.state,
                "torch": torch.get_rng_state(),
                "cuda": torch.cuda.get_rng_state_all() if self.device.type == "cuda" else None,
            },
            "last_eval": self.last_eval,
            "full_eval": self.full_eval,
            "curriculum": self.curriculum,
            # so that an episode ending right after a resume still logs its losses
            "update_metrics": (
                None
                if self._update_metrics is None
                else {k: float(v) for k, v in self._update_metrics.items()}
            ),
        }

    def load_state_dict(self, state: dict[str, Any]) -> None:
        self.agent.load_state_dict(state["agent"])
        buf = {k: v.numpy() if torch.is_tensor(v) else v for k, v in state["buffer"].items()}
        self.buffer.load_state_dict(buf)
        c = state["counters"]
        self.step, self.episodes, self.wall_time = (
            int(c["step"]),
            int(c["episodes"]),
            c["wall_time"],
        )
        self.recent_returns = deque(state["recent_returns"], maxlen=100)
        self.rng.bit_generator.state = state["rng"]["numpy"]
        torch.set_rng_state(state["rng"]["torch"])
        if state["rng"].get("cuda") is not None and self.device.type == "cuda":
            torch.cuda.set_rng_state_all(state["rng"]["cuda"])
        self.last_eval, self.full_eval = state["last_eval"], state["full_eval"]
        self.curriculum = state.get("curriculum")
        m = state.get("update_metrics")
        self._update_metrics = None if m is None else {k: torch.tensor(v) for k, v in m.items()}
        ep = state["episode"]
        if ep["obs"] is not None:
            self._replay_episode(int(ep["seed"]), ep["actions"].numpy(), ep["obs"].numpy())
            self.episode.ret = float(ep["ret"])

    def _replay_episode(self, seed: int, actions: np.ndarray, expected_obs: np.ndarray) -> None:
        """Rebuild the interrupted episode: reset with its seed, replay its actions."""
        self._fresh_env()
        obs, _ = self.env.reset(seed=seed)
        for a in actions:
            obs, *_ = self.env.step(a)
        if not np.array_equal(obs.astype(np.float32), expected_obs):
            self.reporter.log(
                "warning: the replayed episode differs from the checkpoint's; the resumed run "
                "will not match an uninterrupted one exactly"
            )
        self.episode = EpisodeState(seed=seed, actions=list(actions))
        self.obs = obs.astype(np.float32)

    def policy_meta(self) -> dict[str, Any]:
        return {
            "env": self.cfg.env,
            "seed": self.cfg.seed,
            "steps": self.step,
            "episodes": self.episodes,
            "wall_time": round(self.wall_time, 1),
            "last_eval": self.last_eval,
            "full_eval": self.full_eval,
            "torch": str(torch.__version__),
        }

    def save(self) -> None:
        atomic_save(self.state_dict(), self.run_dir / STATE_FILE)
        self.save_policy(self.run_dir / POLICY_FILE)

    def save_policy(self, path: Path) -> None:
        payload = policy_payload(
            self.agent.actor.state_dict(),
            self.cfg.to_dict(),
            self.obs_dim,
            self.act_dim,
            self.policy_meta(),
        )
        atomic_save(payload, path)

    # ------------------------------------------------------------ evaluation
    def evaluate(self, episodes: int) -> dict:
        seeds = [self.cfg.train.eval_seed + i for i in range(episodes)]
        policy = actor_policy(self.agent.actor, self.device)
        return summarize(
            run_episodes(policy, self.cfg.env, seeds),
            self.cfg.train.solved_threshold,
        )

    def full_evaluation(self) -> dict:
        t = self.cfg.train
        seeds = [t.eval_seed + i for i in range(t.solved_episodes)]
        results = evaluate_actor(self.agent.actor, self.cfg.agent, self.cfg.env, seeds)
        summary = summarize(results, t.solved_threshold)
        summary["seeds"] = [seeds[0], seeds[-1]]
        return summary

    # ------------------------------------------------------------------ loop
    def request_stop(self) -> None:
        """Stop after the current env step, with a checkpoint (what the first Ctrl-C does)."""
        self._stop_requested = True

    def _install_sigint(self):
        if threading.current_thread() is not threading.main_thread():
            return None

        def handler(signum, frame):
            if self._stop_requested:  # second Ctrl-C: stop now
                raise KeyboardInterrupt
            self.request_stop()
            self.reporter.log("Ctrl-C: saving a checkpoint and stopping (again to abort)")

        return signal.signal(signal.SIGINT, handler)

    def run(self, total_steps: int | None = None, until_solved: bool = False) -> TrainResult:
        cfg, t = self.cfg, self.cfg.train
        if total_steps is not None:  # `resume --steps N` moves the budget; the config says so
            t.total_steps = total_steps
        total = t.total_steps
        self.run_dir.mkdir(parents=True, exist_ok=True)
        (self.run_dir / "config.yaml").write_text(yaml.safe_dump(cfg.to_dict(), sort_keys=False))
        metrics = MetricsWriter(self.run_dir / METRICS_FILE)
        previous = self._install_sigint()
        self.reporter.start(self.step, total)
        stopped = "budget"
        session_start = time.perf_counter()
        wall_base = self.wall_time
        rate_t, rate_step = session_start, self.step
        steps_per_s = 0.0
        if self.obs is None:
            self._start_episode()
        try:
            while self.step < total:
                if self._stop_requested:
                    stopped = "interrupted"
                    break
                self._env_step(metrics, wall_base, session_start)
                if self.step > t.warmup_steps and len(self.buffer) >= cfg.agent.batch_size:
                    for _ in range(t.updates_per_step):
                        batch = self.agent.batch_to_tensors(
                            self.buffer.sample(cfg.agent.batch_size, self.rng)
                        )
                        self._update_metrics = self.agent.update(batch)
                self.wall_time = wall_base + time.perf_counter() - session_start
                if t.eval_every and self.step % t.eval_every == 0:
                    if self._evaluate(metrics, until_solved):
                        stopped = "solved"
                        break
                if t.checkpoint_every and self.step % t.checkpoint_every == 0:
                    self.save()
                if self.step % 50 == 0:
                    now = time.perf_counter()
                    steps_per_s = (self.step - rate_step) / max(now - rate_t, 1e-9)
                    if now - rate_t > 5:
                        rate_t, rate_step = now, self.step
                    self.reporter.update(self.snapshot(steps_per_s))
        finally:
            self.wall_time = wall_base + time.perf_counter() - session_start
            if previous is not None:
                signal.signal(signal.SIGINT, previous)
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
        )

    def write_plot(self) -> Path | None:
        """``learning_curve.png`` in the run directory (skipped before the first episode ends)."""
        from .plotting import plot_runs

        if self.episodes == 0:
            return None
        return plot_runs([self.run_dir], self.run_dir / PLOT_FILE, title=self.run_dir.name)

    def _fresh_env(self) -> None:
        # A Box2D world keeps history across resets (body and contact ordering), so the same
        # seed and actions give another trajectory in a reused env. A new env per episode makes
        # an episode a pure function of (seed, actions): what exact resume relies on.
        self.env.close()
        self.env = make_env(self.cfg.env)

    def switch_env(self, env_id: str, clear_buffer: bool) -> None:
        """Continue on another env with the same networks, optimizers and temperature.

        The episode in progress is dropped (it is not counted); evaluations now use ``env_id``.
        """
        self.cfg.env = env_id
        probe = make_env(env_id)
        dims = env_dims(probe)
        probe.close()
        if dims != (self.obs_dim, self.act_dim):
            raise UserError(f"{env_id}: observation/action sizes {dims} differ from the agent's")
        if clear_buffer:
            self.buffer.size = self.buffer.pos = 0
        self.last_eval = self.full_eval = None
        self.recent_returns.clear()
        self._start_episode()

    def _start_episode(self) -> None:
        seed = int(self.rng.integers(2**31 - 1))
        self._fresh_env()
        obs, _ = self.env.reset(seed=seed)
        self.obs = obs.astype(np.float32)
        self.episode = EpisodeState(seed=seed)

    def _env_step(self, metrics: MetricsWriter, wall_base: float, session_start: float) -> None:
        if self.step < self.cfg.train.warmup_steps:
            action = self.rng.uniform(-1.0, 1.0, self.act_dim).astype(np.float32)
        else:
            action = self.agent.act(self.obs)
        next_obs, reward, terminated, truncated, _ = self.env.step(action)
        self.buffer.add(self.obs, action, reward, next_obs, terminated)
        self.episode.actions.append(action)
        self.episode.ret += float(reward)
        self.obs = next_obs.astype(np.float32)
        self.step += 1
        if terminated or truncated:
            self.episodes += 1
            self.recent_returns.append(self.episode.ret)
            self.wall_time = wall_base + time.perf_counter() - session_start
            row = {
                "kind": "episode",
                "return": self.episode.ret,
                "length": len(self.episode.actions),
                "fell": is_fall(terminated, reward),
                **self._common(),
                **self._loss_metrics(),
            }
            metrics.write(row)
            self._start_episode()

    def _loss_metrics(self) -> dict[str, float]:
        m = self._update_metrics
        if m is None:
            return {}
        self.last_metrics = {
            k: float(m[k]) for k in ("alpha", "critic_loss", "actor_loss", "entropy", "q_mean")
        }
        return self.last_metrics

    def _common(self) -> dict[str, Any]:
        return {
            "stage": self.cfg.env,
            "step": self.step,
            "episode": self.episodes,
            "wall_time": round(self.wall_time, 2),
        }

    def _eval_row(self, kind: str, summary: dict) -> dict[str, Any]:
        return {
            "kind": kind,
            "return": summary["mean"],
            "return_std": summary["std"],
            "length": summary["mean_length"],
            "fell": summary["falls"],
            **self._common(),
        }

    def _evaluate(self, metrics: MetricsWriter, until_solved: bool) -> bool:
        """The periodic evaluation; with ``until_solved``, the full test once it passes the
        threshold. Returns True when the full test says solved."""
        t = self.cfg.train
        self.reporter.update({**self.snapshot(0.0), "phase": "evaluating"})
        self.last_eval = self.evaluate(t.eval_episodes)
        self.last_eval["step"] = self.step
        metrics.write(self._eval_row("eval", self.last_eval))
        if not until_solved or self.last_eval["mean"] <= t.solved_threshold:
            return False
        self.reporter.log(
            f"step {self.step}: evaluation {self.last_eval['mean']:.1f} > "
            f"{t.solved_threshold:g}; running the {t.solved_episodes}-episode test"
        )
        self.full_eval = self.full_evaluation()
        self.full_eval["step"] = self.step
        metrics.write(self._eval_row("full_eval", self.full_eval))
        self.reporter.log(
            f"{t.solved_episodes}-episode evaluation: "
            f"{self.full_eval['mean']:.1f} +- {self.full_eval['std']:.1f}"
        )
        return self.full_eval["solved"]

    def snapshot(self, steps_per_s: float) -> dict[str, Any]:
        recent = list(self.recent_returns)
        self._loss_metrics()
        return {
            "phase": "warm-up" if self.step < self.cfg.train.warmup_steps else "training",
            "step": self.step,
            "episodes": self.episodes,
            "steps_per_s": steps_per_s,
            "last_return": recent[-1] if recent else None,
            "avg_return": float(np.mean(recent[-10:])) if recent else None,
            "last_eval": self.last_eval["mean"] if self.last_eval else None,
            "wall_time": self.wall_time,
            **self.last_metrics,
        }


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


def train(
    cfg: Config,
    run_dir: str | Path | None = None,
    reporter: Reporter | None = None,
    until_solved: bool = False,
) -> TrainResult:
    """Start a new run in ``run_dir`` (default ``runs/<env>-seed<S>-<time>``) and train it."""
    run_dir = prepare_new_run_dir(run_dir or default_run_dir(cfg))
    trainer = Trainer(cfg, run_dir, reporter)
    return trainer.run(until_solved=until_solved)


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

    Returns a :class:`TrainResult`, or a ``CurriculumResult`` for a curriculum run.
    """
    trainer = load_trainer(path, reporter, device)
    if trainer.curriculum is not None:
        from .curriculum import continue_curriculum

        if total_steps is not None:
            raise UserError(
                "--steps: a curriculum run takes its budgets from its config "
                "(curriculum.walker_steps, curriculum.hardcore_steps)"
            )
        return continue_curriculum(trainer)
    return trainer.run(total_steps=total_steps, until_solved=until_solved)
