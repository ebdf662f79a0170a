"""The TQC agent: actor, critics, target critics, optimizers, log-alpha; ``act`` and ``update``."""

from __future__ import annotations

import copy
import threading
from collections.abc import Mapping

import numpy as np
import torch

from .actor_penalties import actor_penalties
from .adam_moments import step_moments_only
from .agent_state import agent_state_dict, load_agent_state
from .config import AgentConfig
from .critic_worker import CriticWorker
from .losses import actor_loss, quantile_huber_loss, temperature_loss, truncated_target
from .metrics_when_done import MetricsWhenDone
from .networks import SquashedGaussianActor, make_actor, make_critics
from .schedule import target_entropy_at


class TQCAgent:
    """Holds the learner's state; :meth:`update` is one gradient step of TQC (Kuznetsov 2020)."""

    def __init__(
        self, cfg: AgentConfig, obs_dim: int, act_dim: int, device: torch.device | str = "cpu"
    ) -> None:
        self.cfg, self.obs_dim, self.act_dim = cfg, obs_dim, act_dim
        self._worker: CriticWorker | None = None  # start_worker
        self.device = torch.device(device)
        self.actor = make_actor(cfg, obs_dim, act_dim).to(self.device)
        self.critic = make_critics(cfg, obs_dim, act_dim).to(self.device)
        self.critic_target = copy.deepcopy(self.critic).requires_grad_(False)
        self.log_alpha = torch.tensor(
            float(np.log(cfg.init_alpha)), device=self.device, requires_grad=True
        )
        self.target_entropy = target_entropy_at(0, cfg, act_dim)  # H_T; then scheduled_update.py
        adam = {"lr": cfg.lr, "fused": True}  # one kernel per step: 3x the foreach speed on CPU
        self.actor_opt = torch.optim.Adam(self.actor.parameters(), **adam)
        self.critic_opt = torch.optim.Adam(self.critic.parameters(), **adam)
        self.alpha_opt = torch.optim.Adam([self.log_alpha], **adam)
        self.noise = torch.Generator(device=self.device)  # exploration noise, checkpointed
        self.updates = 0
        # the actor's objective: the mean of all atoms (None) or of the lowest L (schedule.py)
        self.actor_lowest_atoms: int | None = None
        self.actor_frozen = False  # agent.actor_update_start: True moves the critics only
        self.actor_smooth: float | None = None  # agent.actor_smooth's weight, once it is on
        self.drop_per_critic = cfg.drop_per_critic  # k of the targets (set_truncation)
        self.anchor: SquashedGaussianActor | None = None  # the initial actor (set_anchor)
        self._online = list(self.critic.parameters())
        self._target = list(self.critic_target.parameters())

    def set_anchor(self) -> None:
        """Freeze a copy of the actor as it is now: ``agent.actor_anchor``'s mu0."""
        self.anchor = copy.deepcopy(self.actor).requires_grad_(False)

    def start_worker(self, flush_denormal: bool = True) -> None:
        """Run the critics' part of every update on a second thread (CPU, 2+ cores;
        :class:`~bipedal_cli.critic_worker.CriticWorker`)."""
        if self._worker is None:
            self._worker = CriticWorker(flush_denormal)

    def stop_worker(self) -> None:
        if self._worker is not None:
            worker, self._worker = self._worker, None
            worker.shutdown()

    def sync(self) -> None:
        """Wait for the critics' step of the last update, which the worker may still be running;
        everything that reads ``critic``/``critic_target`` between updates calls it first."""
        if self._worker is not None:
            self._worker.wait()

    # ------------------------------------------------------------------ acting
    @torch.inference_mode()
    def act(self, obs: np.ndarray, deterministic: bool = False, actor=None) -> np.ndarray:
        """obs: (obs_dim,) or (B, obs_dim) -> action(s) in [-1, 1], by ``actor`` (default: the
        agent's own), sampled with the agent's noise generator unless ``deterministic``."""
        actor = self.actor if actor is None else actor
        x = torch.as_tensor(obs, dtype=torch.float32, device=self.device)
        single = x.dim() == 1
        x = x.unsqueeze(0) if single else x
        if deterministic:
            action = actor.deterministic(x)
        else:
            action = actor.sample_action(x, generator=self.noise)
        action = action.cpu().numpy()
        return action[0] if single else action

    # ---------------------------------------------------------------- learning
    def batch_to_tensors(self, batch: dict[str, np.ndarray]) -> dict[str, torch.Tensor]:
        return {k: torch.as_tensor(v, device=self.device) for k, v in batch.items()}

    def set_learning_rate(self, lr: float) -> None:
        """The Adam step size of actor, critics and temperature from the next update on (after
        the critics' last step, which may still be running on the worker)."""
        self.sync()
        for opt in (self.actor_opt, self.critic_opt, self.alpha_opt):
            for group in opt.param_groups:
                group["lr"] = lr

    def learning_rate(self) -> float:
        return float(self.actor_opt.param_groups[0]["lr"])

    def set_truncation(self, drop_per_critic: int) -> None:
        """k, the atoms per critic the next updates' targets drop (after the critics' last step,
        whose target the worker may still be computing with the old k)."""
        if drop_per_critic != self.drop_per_critic:
            self.sync()
            self.drop_per_critic = drop_per_critic

    def update(self, batch: dict[str, torch.Tensor]) -> Mapping[str, torch.Tensor]:
        """One TQC step on a batch; returns detached 0-dim metric tensors (no host sync here).

        As in the paper's algorithm (and the TQC authors' code), the three gradients
        grad J_Z(psi), grad J_pi(phi) and grad J(alpha) are all taken at the current
        parameters; then every parameter moves. So the critics' part (a' ~ pi(.|s'), the
        target, eq. 1, Adam, Polyak) and the actor's part (eqs. 2-3, Adam) meet in two places
        only: a' reads the actor before the actor's step, and the actor loss reads the critics
        before the critics' step. With a worker thread (:meth:`start_worker`) the critics'
        part runs there and the actor's part on the calling thread (ATen releases the GIL
        inside each op); two events order those reads before the writes. The call returns
        once the actor has moved, while the critics' step may still run on the worker (it
        overlaps acting and stepping the env); the next update, :meth:`sync` and reading the
        returned metrics wait for it. Every operation sees the same values in the same order
        as without the worker, so the results are equal to the bit.
        """
        self.sync()  # the actor loss reads the critics: their last step must be done
        obs, alpha = batch["obs"], self.log_alpha.detach().exp()
        eps = self.update_noise(obs)
        if self._worker is None:
            critic_metrics = self.critic_gradients(batch, eps[1], alpha)
            actor_metrics = self.actor_gradients(obs, eps[0], alpha)
            self.critic_step()
            self.actor_step()
            self.updates += 1
            return {**critic_metrics, **actor_metrics, "alpha": alpha}
        actor_read, critic_read = threading.Event(), threading.Event()
        job = self._worker.submit(self._critic_part, batch, eps[1], alpha, actor_read, critic_read)
        try:
            actor_metrics = self.actor_gradients(obs, eps[0], alpha)
        finally:
            critic_read.set()  # set even after an error: never leave the worker waiting
            actor_read.wait()  # the worker sets it even when it fails
        self._worker.hold(job)
        self.actor_step()
        self.updates += 1
        return MetricsWhenDone(job, {**actor_metrics, "alpha": alpha})

    def _critic_part(
        self,
        batch: dict[str, torch.Tensor],
        eps: torch.Tensor,
        alpha: torch.Tensor,
        actor_read: threading.Event,
        critic_read: threading.Event,
    ) -> dict[str, torch.Tensor]:
        """The worker's share of :meth:`update`: critic gradients, then (after the actor loss
        has read the critics) their step."""
        try:
            metrics = self.critic_gradients(batch, eps, alpha, actor_read)
        finally:
            actor_read.set()
        critic_read.wait()
        self.critic_step()
        return metrics

    def critic_gradients(
        self,
        batch: dict[str, torch.Tensor],
        eps: torch.Tensor,
        alpha: torch.Tensor,
        actor_read: threading.Event | None = None,
    ) -> dict[str, torch.Tensor]:
        """grad J_Z(psi) of eq. (1) against the truncated target, into the critics' .grad."""
        cfg = self.cfg
        with torch.no_grad():
            next_obs = batch["next_obs"]
            next_action, next_log_prob = self.actor.sample(next_obs, eps=eps)  # (B, A), (B,)
            if actor_read is not None:
                actor_read.set()  # done with the actor: its step may go ahead
            next_atoms = self.critic_target(next_obs, next_action)  # (B, N, M)
            target = truncated_target(
                next_atoms,
                batch["reward"],
                batch["terminated"],
                next_log_prob,
                alpha,
                cfg.gamma,
                self.drop_per_critic,
                batch.get("discount") if cfg.n_step > 1 else None,
            )  # (B, K)
        atoms = self.critic(batch["obs"], batch["action"])  # (B, N, M)
        critic_loss = quantile_huber_loss(atoms, target)
        self.critic_opt.zero_grad(set_to_none=True)
        critic_loss.backward()
        return {"critic_loss": critic_loss.detach(), "q_mean": atoms.detach().mean()}

    def critic_step(self) -> None:
        """Adam on the critics, then Polyak: psi_bar <- tau psi + (1 - tau) psi_bar."""
        self.critic_opt.step()
        with torch.no_grad():
            torch._foreach_lerp_(self._target, self._online, self.cfg.tau)

    def actor_gradients(
        self, obs: torch.Tensor, eps: torch.Tensor, alpha: torch.Tensor
    ) -> dict[str, torch.Tensor]:
        """grad J_pi(phi) of eq. (2) through the critics (their weights frozen), grad J(alpha)
        of eq. (3)."""
        new_action, log_prob, mean = self.actor.sample_with_mean(obs, eps=eps)  # (B, A)
        new_atoms = self.critic(obs, new_action, detach_params=True)  # (B, N, M)
        pi_loss = actor_loss(log_prob, new_atoms, alpha, self.actor_lowest_atoms)
        penalty = actor_penalties(self, obs, mean)  # anchor, smoothness; None if neither
        if penalty is not None:
            pi_loss = pi_loss + penalty
        self.actor_opt.zero_grad(set_to_none=True)
        pi_loss.backward()
        alpha_loss = temperature_loss(self.log_alpha, log_prob, self.target_entropy)
        self.alpha_opt.zero_grad(set_to_none=True)
        alpha_loss.backward()
        return {
            "actor_loss": pi_loss.detach(),
            "alpha_loss": alpha_loss.detach(),
            "entropy": -log_prob.detach().mean(),
        }

    def actor_step(self) -> None:
        """Adam on the actor and the temperature; while :attr:`actor_frozen` a step of size zero,
        theta <- theta - 0 * m_hat / (sqrt(v_hat) + eps): the parameters stay, the moments
        average the gradients (a fresh Adam's first steps are lr * sign(g) on every weight)."""
        for opt in (self.actor_opt, self.alpha_opt):
            if self.actor_frozen:
                step_moments_only(opt)
            else:
                opt.step()

    def update_noise(self, obs: torch.Tensor) -> torch.Tensor:
        """(2, B, A): eps[0] draws a ~ pi(.|s) for eqs. 2-3, eps[1] a' ~ pi(.|s') for the target."""
        shape = (2, obs.shape[0], self.act_dim)
        return torch.randn(shape, generator=self.noise, device=self.device, dtype=obs.dtype)

    # ------------------------------------------------------------- persistence
    def state_dict(self) -> dict:
        return agent_state_dict(self)

    def load_state_dict(self, state: dict) -> None:
        load_agent_state(self, state)
