"""Who acts in a restarted run's refill (``train.refill_policies``).

A restart file leaves the replay buffer out, so a run continued from one first acts
``train.refill_steps`` policy steps without updates to fill it again. With its own actor alone
the buffer holds one policy's transitions, where the run's own buffer held those of every
policy of its last million steps, and the run loses its level (docs/hardcore.md, session 52).
With ``train.refill_policies`` the refill's episodes are played by earlier policies in turn:
episode e by policy e mod K, sampling from its own squashed Gaussian with the agent's noise
generator, so that a resumed refill draws what a straight one would.
"""

from __future__ import annotations

from typing import Any

import torch

from .checkpoint import matching_actor_state
from .envs import policy_dims
from .errors import UserError
from .networks import make_actor


def refill_policy_option(index: int) -> str:
    return f"train.refill_policies[{index}]"


def load_refill_actors(cfg: Any, obs_dim: int, act_dim: int, device: torch.device) -> list[Any]:
    """The actors of ``cfg.train.refill_policies``, in order, on ``device``; a file that is not
    a policy of this config's shape and inputs is one line naming it
    (:func:`~bipedal_cli.checkpoint.matching_actor_state`). The run's random streams are left
    as they were, so a run that loads them in its refill draws what a straight one would."""
    actors = []
    for index, path in enumerate(cfg.train.refill_policies):
        weights = matching_actor_state(path, refill_policy_option(index), cfg, obs_dim, act_dim)
        with torch.random.fork_rng(devices=[]):  # the initial weights' draws leave no trace
            actor = make_actor(cfg.agent, obs_dim, act_dim)
        actor.load_state_dict(weights)
        actors.append(actor.to(device).eval())
    return actors


def checked_refill_actors(cfg: Any) -> list[Any]:
    """The actors of ``cfg.train.refill_policies`` on CPU, read before a restart's run directory
    is made, so that a bad file stops it in one line; the trainer then acts with these. A restart
    file's config keeps the list its own run was refilled with, so the line says how to name
    others, or none."""
    try:
        return load_refill_actors(cfg, *policy_dims(cfg.env, cfg.agent), torch.device("cpu"))
    except UserError as err:
        raise UserError(
            f"{err}; name others with --refill-policy, or none with --set train.refill_policies=[]"
        ) from None


def refill_policy_index(step: int, refill_until: int, episodes: int, n_policies: int) -> int | None:
    """Which of the ``n_policies`` refill policies plays policy step ``step`` + 1, in the episode
    after the ``episodes`` finished ones: ``episodes mod n_policies`` while the refill lasts
    (``step < refill_until``), None after it or without refill policies (the agent's actor)."""
    if n_policies == 0 or step >= refill_until:
        return None
    return episodes % n_policies


def refill_actor(trainer: Any) -> Any | None:
    """The actor that plays the trainer's next policy step if it is a refill policy's (loaded on
    first use, also when a run is resumed inside its refill), else None."""
    index = refill_policy_index(
        trainer.step, trainer.refill_until, trainer.episodes, len(trainer.cfg.train.refill_policies)
    )
    if index is None:
        return None
    if trainer.refill_actors is None:
        trainer.refill_actors = load_refill_actors(
            trainer.cfg, trainer.obs_dim, trainer.act_dim, trainer.device
        )
    return trainer.refill_actors[index]
