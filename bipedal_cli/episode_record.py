"""A training episode's start and what it leaves behind: how the next one begins (fresh, a probe
of the deterministic policy or a restart near a fall: ``train.fall_restart``), and the episode
counter, the recent returns and falls the display shows, a remembered fall and the episode's
``metrics.csv`` row once it ends."""

from __future__ import annotations

from typing import Any

from .episodes import FinishedEpisode, curation_on, obstacle_mix_on
from .fall_restarts import draws_probe, remembers_fall, restarts_on
from .metrics import MetricsWriter
from .schedule import fall_penalty_at


def start_episode(trainer: Any) -> None:
    """Start ``trainer``'s next episode: a restart near a remembered fall (with probability
    ``train.fall_restart`` once restarts are on), else a fresh one on a new seed, a probe with
    probability ``train.fall_restart_probe``. The draws come from the trainer's RNG in that
    order, and only for the features that are on."""
    t, step = trainer.cfg.train, trainer.step
    restart = trainer.fall_memory.draw(trainer.rng, t) if restarts_on(t, step) else None
    seed, prefix = restart or (int(trainer.rng.integers(2**31 - 1)), None)
    probe = restart is None and draws_probe(trainer.rng, t, step)
    curated, penalty = curation_on(t, step), fall_penalty_at(step, t)
    trainer.runner.start(seed, curated, penalty, prefix, probe, obstacle_mix_on(t, step))


def record_episode(trainer: Any, ep: FinishedEpisode, metrics: MetricsWriter) -> None:
    """Book ``ep``, just finished by ``trainer``'s runner (whose episode state is still its own).

    A fresh episode (a probe of the deterministic policy among them, logged as kind ``probe``)
    counts in the recent returns and falls, and its fall may be remembered for restarts
    (:func:`~bipedal_cli.fall_restarts.remembers_fall`); a restarted one (begun near a fall) is
    logged as kind ``restart`` and counts in neither, so the display's figures stay those of
    the policy's own episodes."""
    trainer.episodes += 1
    fresh = ep.restart_env_steps is None
    if fresh:
        trainer.recent_returns.append(ep.env_ret)
        trainer.recent_falls.append(bool(ep.fell))
    if remembers_fall(trainer.cfg.train, trainer.step, fresh, ep.probe, bool(ep.fell)):
        e = trainer.runner.episode
        trainer.fall_memory.remember(e.seed, e.actions, trainer.act_dim)
    row = {
        "kind": ("probe" if ep.probe else "episode") if fresh else "restart",
        "return": ep.env_ret,
        "shaped_return": ep.ret,
        "length": ep.env_steps,
        "fell": ep.fell,
        "restart_from": ep.restart_env_steps,
        **trainer.row_counters(),
        **trainer.loss_metrics(),
    }
    metrics.write(row)
