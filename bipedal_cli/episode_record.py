"""What a finished training episode leaves behind: the episode counter, the recent returns and
falls the display shows, a remembered fall (``train.fall_restart``) and its ``metrics.csv`` row."""

from __future__ import annotations

from typing import Any

from .episodes import FinishedEpisode
from .fall_restarts import restarts_on
from .metrics import MetricsWriter


def record_episode(trainer: Any, ep: FinishedEpisode, metrics: MetricsWriter) -> None:
    """Book ``ep``, just finished by ``trainer``'s runner (whose episode state is still its own).

    A fresh episode counts in the recent returns and falls, and its fall is remembered for
    restarts; a restarted one (begun near a fall) is logged as kind ``restart`` and counts in
    neither, so the display's figures stay those of the policy's own episodes."""
    trainer.episodes += 1
    fresh = ep.restart_env_steps is None
    if fresh:
        trainer.recent_returns.append(ep.env_ret)
        trainer.recent_falls.append(bool(ep.fell))
    if fresh and ep.fell and restarts_on(trainer.cfg.train, trainer.step):
        e = trainer.runner.episode
        trainer.fall_memory.remember(e.seed, e.actions, trainer.act_dim)
    row = {
        "kind": "episode" if fresh else "restart",
        "return": ep.env_ret,
        "shaped_return": ep.ret,
        "length": ep.env_steps,
        "fell": ep.fell,
        "restart_from": ep.restart_env_steps,
        **trainer.row_counters(),
        **trainer.loss_metrics(),
    }
    metrics.write(row)
