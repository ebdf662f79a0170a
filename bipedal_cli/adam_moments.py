"""Adam's moments of the actor and the critics: left out of a restart file, and estimated again
by the run that restarts from it, once its refill ends.

Adam keeps two moments per weight, so the actor's and critics' optimizers are twice the size of
the networks: with critics 512 wide, a restart file with them was 33 MiB, and without them (its
metrics zlib-packed too) about 16 MiB. A restart file leaves them out
(:func:`without_moments`); the temperature's (one scalar) stays. Its run restarts with an
emptied replay buffer anyway (the same agent, not the same run). At the first learning step
after the refill, before the first update, it estimates the moments again
(:func:`estimate_moments`): K Adam steps of size zero on fresh batches of the refilled buffer,
with the gradients of the TQC losses at the file's parameters. The networks and the targets do
not move, so those K steps change no weight, only what Adam knows of the gradients' scale. A
fresh Adam instead would move every weight by about lr * sign(g) on its first steps.
"""

from __future__ import annotations

from typing import Any

import torch

NETWORK_OPTIMIZERS = ("actor_opt", "critic_opt")  # in an agent's state dict


def step_moments_only(opt: torch.optim.Optimizer) -> None:
    """One Adam step of size zero: m <- b1 m + (1 - b1) g, v <- b2 v + (1 - b2) g^2, t <- t + 1,
    then theta <- theta - 0 * m_hat / (sqrt(v_hat) + eps). The moments take the gradient in;
    the parameters stay, bit for bit."""
    rates = [group["lr"] for group in opt.param_groups]
    for group in opt.param_groups:
        group["lr"] = 0.0
    try:
        opt.step()
    finally:
        for group, lr in zip(opt.param_groups, rates, strict=True):
            group["lr"] = lr


def without_moments(agent_state: dict[str, Any]) -> dict[str, Any]:
    """An agent's state dict whose actor and critic optimizers keep their settings
    (``param_groups``: learning rate, betas) and none of their per-weight moments."""
    emptied = {key: {**agent_state[key], "state": {}} for key in NETWORK_OPTIMIZERS}
    return {**agent_state, **emptied}


def moments_missing(agent: Any) -> bool:
    """True for an agent loaded from a restart file written without moments (until
    :func:`estimate_moments`); an agent that has made an update has them."""
    return not agent.critic_opt.state and not agent.actor_opt.state


def moment_batches(opt: torch.optim.Optimizer) -> int:
    """K = 1 / (1 - b2) (1,000 with b2 = 0.999): the horizon of Adam's second moment. After K
    steps from zero, v_hat = v / (1 - b2^K) is an average of g^2 over the K batches."""
    beta2 = float(opt.param_groups[0]["betas"][1])
    return max(1, round(1.0 / (1.0 - beta2)))


def estimate_moments(trainer: Any, batch_size: int) -> int:
    """The actor's and critics' moments of a restarted run, from K = :func:`moment_batches`
    batches of ``batch_size`` transitions drawn from its buffer with its generator; returns K.
    Reproducible: the draws come from the run's checkpointed generators."""
    agent = trainer.agent
    batches = moment_batches(agent.critic_opt)
    trainer.reporter.log(
        f"step {trainer.step:,}: estimating Adam's moments from {batches:,} batches of the "
        "refilled buffer (the restart file leaves them out); no weight moves"
    )
    for _ in range(batches):
        batch = agent.batch_to_tensors(trainer.buffer.sample(batch_size, trainer.rng))
        accumulate_moments(agent, batch)
    return batches


def accumulate_moments(agent: Any, batch: dict[str, torch.Tensor]) -> None:
    """The gradients of :meth:`TQCAgent.update <bipedal_cli.agent.TQCAgent.update>` on
    ``batch``, into the actor's and critics' Adam moments only (:func:`step_moments_only`): no
    weight, target or temperature moves."""
    agent.sync()
    eps, alpha = agent.update_noise(batch["obs"]), agent.log_alpha.detach().exp()
    agent.critic_gradients(batch, eps[1], alpha)
    agent.actor_gradients(batch["obs"], eps[0], alpha)
    step_moments_only(agent.critic_opt)
    step_moments_only(agent.actor_opt)
