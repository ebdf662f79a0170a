"""A :class:`~bipedal_cli.agent.TQCAgent`'s state as a dict of tensors and back: networks,
optimizers, temperature, noise generator, update counter and the anchor (checkpoint.py writes
and checks the files)."""

from __future__ import annotations

from typing import Any

import torch

from .anchor import anchored


def agent_state_dict(agent: Any) -> dict:
    """Everything an exact resume needs of the agent (after the critics' last step)."""
    agent.sync()
    return {
        "actor": agent.actor.state_dict(),
        "critic": agent.critic.state_dict(),
        "critic_target": agent.critic_target.state_dict(),
        "log_alpha": agent.log_alpha.detach().cpu(),
        "actor_opt": agent.actor_opt.state_dict(),
        "critic_opt": agent.critic_opt.state_dict(),
        "alpha_opt": agent.alpha_opt.state_dict(),
        "noise_rng": agent.noise.get_state(),
        "updates": agent.updates,
        "anchor": None if agent.anchor is None else agent.anchor.state_dict(),
    }


def load_agent_state(agent: Any, state: dict) -> None:
    """The inverse of :func:`agent_state_dict`, into an agent built from the same config."""
    agent.sync()
    agent.actor.load_state_dict(state["actor"])
    agent.critic.load_state_dict(state["critic"])
    agent.critic_target.load_state_dict(state["critic_target"])
    with torch.no_grad():
        agent.log_alpha.copy_(state["log_alpha"])
    agent.actor_opt.load_state_dict(state["actor_opt"])
    agent.critic_opt.load_state_dict(state["critic_opt"])
    agent.alpha_opt.load_state_dict(state["alpha_opt"])
    agent.noise.set_state(state["noise_rng"])
    agent.updates = int(state["updates"])
    agent.anchor = None
    if anchored(agent.cfg) or state.get("anchor") is not None:
        agent.set_anchor()  # a branch into an anchor (only up to actor_update_start) keeps it
        if state.get("anchor") is not None:  # older states have no key
            agent.anchor.load_state_dict(state["anchor"])
