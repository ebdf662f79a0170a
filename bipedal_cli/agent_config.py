"""The agent's section of a config: TQC + D2RL hyperparameters and what the policy is made of
(action repeat, history, encoder), as a typed dataclass (:mod:`bipedal_cli.config` fills it)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass
class AgentConfig:
    """TQC + D2RL hyperparameters (paper Table 1; see configs/walker.yaml for the choices)."""

    gamma: float = 0.98
    """Discount factor."""
    lr: float = 7.3e-4
    """Adam learning rate for actor, critics and temperature (rl-zoo's for this env; Table 1's
    mean, 3.296e-4, is configs/paper.yaml; docs/tuning.md compares them)."""
    lr_final: float | None = None
    """Learning rate at ``lr_decay_end``, reached linearly from ``lr`` at ``lr_decay_start``
    (actor, critics and temperature alike; rl-zoo decays Hardcore's). None: ``lr`` throughout."""
    lr_decay_start: int = 0
    """Policy step where the decay begins (``lr`` up to here)."""
    lr_decay_end: int = 0
    """Policy step where the decay ends (``lr_final`` from here on)."""
    batch_size: int = 64
    """Transitions per gradient step."""
    batch_size_final: int | None = None
    """Transitions per gradient step after ``batch_size_start``: a larger batch lowers the
    gradient's noise where a smaller learning rate would slow the learning further. None:
    ``batch_size`` throughout."""
    batch_size_start: int = 0
    """Policy step after which the updates draw ``batch_size_final`` transitions."""
    tau: float = 0.005
    """Polyak rate of the target critics: target <- tau * online + (1 - tau) * target."""
    n_critics: int = 5
    """N: critics in the ensemble."""
    n_quantiles: int = 25
    """M: quantile atoms per critic."""
    drop_per_critic: int = 2
    """k: atoms dropped from the top of the pooled target per critic (k * N in all)."""
    drop_per_critic_final: int | None = None
    """k after ``drop_per_critic_start``: more truncation, a more pessimistic critic under the
    same actor. None: ``drop_per_critic`` throughout."""
    drop_per_critic_start: int = 0
    """Policy step after which the targets drop ``drop_per_critic_final`` atoms per critic."""
    actor_hidden: int = 512
    """Width of the actor's hidden layers."""
    critic_hidden: int = 256
    """Width of each critic's hidden layers."""
    n_layers: int = 2
    """Hidden layers per network."""
    d2rl: bool = True
    """Concatenate the network input to every hidden layer's output (False: plain MLP)."""
    init_alpha: float = 1.0
    """Initial entropy temperature alpha."""
    target_entropy: float | None = None
    """Target entropy H_T; None means -dim(A)."""
    target_entropy_final: float | None = None
    """H_T at ``target_entropy_decay_end``, reached linearly from H_T at
    ``target_entropy_decay_start``: a training policy that ends closer to the deterministic one
    that is scored. None: H_T throughout."""
    target_entropy_decay_start: int = 0
    """Policy step where the target entropy starts to move (H_T up to here)."""
    target_entropy_decay_end: int = 0
    """Policy step where it reaches ``target_entropy_final`` (constant after)."""
    log_std_min: float = -20.0
    """Lower clamp of the actor's log standard deviation."""
    log_std_max: float = 2.0
    """Upper clamp of the actor's log standard deviation."""
    action_repeat: int = 1
    """k: the policy holds each action for k env steps (their rewards summed). Part of the
    policy: evaluation, recording and export apply it too."""
    history: int = 1
    """H: the networks see the last H observations (oldest first, H * 24 inputs). Part of the
    policy, like ``action_repeat``."""
    encoder: str = "none"
    """What the actor and the critics read of the H observations: ``none``, the flattened
    window; ``lstm``, an LSTM's last hidden state over the window beside the newest observation
    (:mod:`~bipedal_cli.encoders`; the critics share one, the actor has its own)."""
    encoder_hidden: int = 64
    """Width of the ``lstm`` encoder's hidden and cell state."""
    n_step: int = 1
    """n: targets sum n rewards, y = sum_{j<n} gamma^j r_{t+j} + gamma^n (1 - d) (z - alpha
    log pi); an episode's end inside the n steps cuts the sum (termination also the
    bootstrap)."""
    actor_cvar: float | None = None
    """c in (0, 1]: from ``actor_cvar_start`` on, the actor maximises the mean of the lowest
    c N M (rounded half up) of the critics' N*M pooled atoms, the CVaR_c of their mixture,
    instead of the mean of all (eq. 2): a risk-averse policy that weighs a fall in the return's
    lower tail more. None: eq. 2 throughout."""
    actor_cvar_start: int = 0
    """Policy step after which the actor's objective is ``actor_cvar``'s (the mean up to it)."""
    actor_anchor: float | None = None
    """beta: with ``train.init_policy``, the actor's loss adds beta E_s ||mu(s) - mu0(s)||^2,
    the squared distance of its deterministic action from the initial policy's on the batch's
    states, so that it moves where new critics agree and stays where they are still wrong
    (TD3+BC's term). None: off."""
    actor_anchor_kl: float | None = None
    """beta: with ``train.init_policy``, the actor's loss adds beta E_s KL(pi(.|s) || pi0(.|s)),
    its divergence from the initial policy: mean and spread, where ``actor_anchor`` holds the
    mean action only. None: off."""
    actor_smooth: float | None = None
    """lambda: from ``actor_smooth_start`` on, the actor's loss adds
    lambda E_s ||mu(s) - mu(s + sigma xi)||_2, xi ~ N(0, I), the distance of its deterministic
    action at a state from the one at a jittered copy (CAPS's spatial term, Mysore et al.
    2021): a policy that a small change of what it sees moves less. None: off."""
    actor_smooth_sigma: float = 0.02
    """sigma: the standard deviation of the jitter, in the observation's own units."""
    actor_smooth_start: int = 0
    """Policy step after which ``actor_smooth`` applies."""
    actor_update_start: int = 0
    """Policy step after which the actor and the temperature learn; up to it only the critics do,
    learning the value of a fixed actor (a run from ``train.init_policy`` warms its new critics
    up this way). 0: all three from the first update."""
