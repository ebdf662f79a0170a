"""A run's periodic evaluation: deterministic episodes on fixed seeds every ``train.eval_every``
policy steps, the best and kept policies saved, and with ``--until-solved`` the 100-episode test
once an evaluation passes the threshold. Functions of a :class:`~bipedal_cli.train.Trainer`.
"""

from __future__ import annotations

from typing import Any

from .checkpoint import BEST_POLICY_FILE, POLICIES_DIR, recorded_evaluation
from .evaluation import actor_policy, evaluate_actor, run_episodes, summarize
from .metrics import MetricsWriter


def evaluate_on_eval_seeds(trainer: Any, episodes: int) -> dict:
    """``episodes`` deterministic episodes on seeds from ``train.eval_seed`` (in process)."""
    seeds = [trainer.cfg.train.eval_seed + i for i in range(episodes)]
    policy = actor_policy(trainer.agent.actor, trainer.device)
    return summarize(
        run_episodes(policy, trainer.cfg.env, seeds, trainer.cfg.agent),
        trainer.cfg.train.solved_threshold,
    )


def full_evaluation(trainer: Any) -> dict:
    """The ``solved_episodes`` test on seeds ``train.eval_seed`` on (spread over every core)."""
    t = trainer.cfg.train
    seeds = [t.eval_seed + i for i in range(t.solved_episodes)]
    results = evaluate_actor(trainer.agent.actor, trainer.cfg.agent, trainer.cfg.env, seeds)
    summary = summarize(results, t.solved_threshold)
    summary["seeds"] = [seeds[0], seeds[-1]]
    return summary


def _eval_row(trainer: Any, kind: str, summary: dict) -> dict[str, Any]:
    return {
        "kind": kind,
        "return": summary["mean"],
        "return_std": summary["std"],
        "length": summary["mean_length"],
        "fell": summary["falls"],
        **trainer.row_counters(),
    }


def periodic_evaluation(trainer: Any, metrics: MetricsWriter, until_solved: bool) -> str | None:
    """The periodic evaluation; with ``until_solved``, the full test once it passes the
    threshold. Then ``trainer.on_evaluation``, after every evaluation. Returns "solved" when the
    full test says so, else "pruned" when ``on_evaluation`` asks to stop, else None."""
    t = trainer.cfg.train
    trainer.reporter.update({**trainer.snapshot(0.0), "phase": "evaluating"})
    trainer.last_eval = trainer.evaluate(t.eval_episodes)
    trainer.last_eval["step"] = trainer.step
    metrics.write(_eval_row(trainer, "eval", trainer.last_eval))
    best = recorded_evaluation(trainer.run_dir / BEST_POLICY_FILE, trainer.cfg.env)
    if best is None or trainer.last_eval["mean"] > best:
        trainer.save_policy(trainer.run_dir / BEST_POLICY_FILE)
    if t.keep_policies:
        (trainer.run_dir / POLICIES_DIR).mkdir(exist_ok=True)
        trainer.save_policy(trainer.run_dir / POLICIES_DIR / f"step-{trainer.step}.pt")
    solved = False
    if until_solved and trainer.last_eval["mean"] > t.solved_threshold:
        solved = _full_test(trainer, metrics)
    stop = trainer.on_evaluation is not None and trainer.on_evaluation(trainer)
    if solved:
        return "solved"
    return "pruned" if stop else None


def _full_test(trainer: Any, metrics: MetricsWriter) -> bool:
    """The ``solved_episodes`` test (100 episodes): True when it passes."""
    t = trainer.cfg.train
    trainer.reporter.log(
        f"step {trainer.step}: evaluation {trainer.last_eval['mean']:.1f} > "
        f"{t.solved_threshold:g}; running the {t.solved_episodes}-episode test"
    )
    trainer.full_eval = full_evaluation(trainer)
    trainer.full_eval["step"] = trainer.step
    metrics.write(_eval_row(trainer, "full_eval", trainer.full_eval))
    trainer.reporter.log(
        f"{t.solved_episodes}-episode evaluation: "
        f"{trainer.full_eval['mean']:.1f} +- {trainer.full_eval['std']:.1f}"
    )
    return bool(trainer.full_eval["solved"])
