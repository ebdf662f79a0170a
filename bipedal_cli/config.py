"""Typed configuration: dataclasses with defaults, filled from YAML, overridden by ``--set``.

Precedence, resolved in one place (:func:`resolve_config`): ``--set key=value`` wins over the
YAML file, the YAML file over the dataclass defaults. Unknown keys and wrong types raise
:class:`~bipedal_cli.errors.UserError` naming the key.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .config_yaml import load_yaml, parse_override, set_nested
from .env_ids import canonical_env_id
from .typed_fill import fill_dataclass
from .validation import validate


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
    actor_update_start: int = 0
    """Policy step after which the actor and the temperature learn; up to it only the critics do,
    learning the value of a fixed actor (a run from ``train.init_policy`` warms its new critics
    up this way). 0: all three from the first update."""


@dataclass
class TrainConfig:
    """The training loop: budget, warm-up, evaluation and checkpoint cadence."""

    total_steps: int = 300_000
    """Policy steps to train for (``--steps`` overrides); each is ``agent.action_repeat`` env
    steps, so without action repeat these are env steps."""
    warmup_steps: int = 1000
    """Random-action steps before learning starts (Table 1's 'learning starts'); with
    ``init_policy``, that actor's own sampled actions instead."""
    buffer_size: int = 1_000_000
    """Replay buffer capacity in transitions."""
    updates_per_step: int = 1
    """Gradient steps per policy step after warm-up (UTD ratio)."""
    updates_per_step_final: int | None = None
    """Gradient steps per policy step after ``updates_per_step_start``: more learning from the
    same experience (REDQ's lever; costs that many updates' time). None: ``updates_per_step``."""
    updates_per_step_start: int = 0
    """Policy step after which each step makes ``updates_per_step_final`` updates."""
    eval_every: int = 5_000
    """Policy steps between periodic deterministic evaluations (0: never)."""
    eval_episodes: int = 5
    """Episodes per periodic evaluation."""
    solved_episodes: int = 100
    """Episodes of the full evaluation that decides 'solved'."""
    solved_threshold: float = 300.0
    """Mean return above which the environment counts as solved."""
    checkpoint_every: int = 10_000
    """Policy steps between training-state checkpoints."""
    threads: int = 0
    """CPU threads for training; 0 means all cores. With 2 or more (on CPU, with
    ``split_update``) each update runs its critics' and actor's parts on two threads with
    threads // 2 intra-op threads each; the result equals a 1-thread run's to the bit."""
    split_update: bool = True
    """Run the critics' and the actor's parts of each update concurrently when threads >= 2
    (batch-64 matrix products split badly across cores; the two parts split well)."""
    flush_denormal: bool = True
    """Flush denormal floats to zero on CPU: Adam moments of dead units decay into the denormal
    range within a few thousand steps and then slow every update down by up to 2x."""
    replay_keep_below: float | None = None
    """FORK's replay curation: an episode's transitions enter the replay buffer only if it fell
    or its env return is below this (FORK: 250); the others are dropped. None: every episode."""
    replay_curation_start: int = 0
    """Policy step from which episodes (those that start there or later) are curated."""
    replay_recency: float | None = None
    """eta_0 in (0, 1): Emphasizing Recent Experience (ERE, the paper's future work): update k
    of every 1000 draws from the newest max(N eta^k, ``replay_recent_min``) of the N stored
    transitions (:mod:`~bipedal_cli.recency`; Wang and Ross use 0.996). null: uniform replay."""
    replay_recency_end: int | None = None
    """Policy step where eta reaches 1 (uniform replay), linearly from eta_0 at step 0, as ERE
    anneals it over training. null: eta_0 throughout."""
    replay_recent_min: int = 5000
    """c_min: the fewest newest transitions an ERE update draws from (Wang and Ross: 5000)."""
    keep_policies: bool = False
    """Also save the policy of every periodic evaluation, ``policies/step-<N>.pt`` (about 1.4 MB
    each with Hardcore's networks), to choose among them afterwards on seeds that did not pick
    them (``bipedal select``). Changes nothing in training."""
    eval_seed: int = 1_000_000
    """First env seed of evaluation episodes (kept apart from training seeds)."""
    fall_penalty: float | None = None
    """Training only: the reward the learner sees when the walker falls, instead of the env's
    -100 (null: unchanged). Evaluations always score the env's own reward."""
    fall_penalty_final: float | None = None
    """Training only: the fall penalty moves linearly from ``fall_penalty`` to this between
    policy steps ``fall_penalty_ramp_start`` and ``fall_penalty_ramp_end``, and stays there; an
    episode keeps the penalty of the step it starts at. null: ``fall_penalty`` throughout."""
    fall_penalty_ramp_start: int = 0
    """Policy step where the ramp starts (an episode starting there or before: ``fall_penalty``)."""
    fall_penalty_ramp_end: int = 0
    """Policy step where it reaches ``fall_penalty_final`` (episodes from there on see that)."""
    reward_scale: float = 1.0
    """Training only: the learner's rewards (fall penalty included) are multiplied by this."""
    init_policy: str | None = None
    """A policy file whose actor a new run starts from, instead of a random one (critics,
    temperature and replay start afresh). Its action repeat, history and actor shape must be
    this config's. Read once, when the run starts: a resume does not need it. null: random."""
    init_policy_sha256: str | None = None
    """The sha256 of ``init_policy``'s bytes, checked when the run starts, so that a config
    names one file's content, not whatever lies at that path. null: not checked."""
    fall_restart: float = 0.0
    """Training only: the probability that an episode, instead of starting afresh, restarts a
    little before where a recent episode fell (the same terrain, its actions replayed up to
    there, nothing stored), so that the learner sees more of what it falls at. 0: off."""
    fall_restart_back: int = 30
    """A restart begins k policy steps before the fall, k drawn uniformly from
    ``fall_restart_back_min`` .. this."""
    fall_restart_back_min: int = 1
    """The least k: closer to a fall than a few policy steps, no action saves the walker, and a
    restart there only repeats the fall."""
    fall_restart_horizon: int | None = 100
    """Policy steps a restarted episode plays before it is cut (a truncation: the value
    bootstraps); null: to the episode's own end."""
    fall_restart_memory: int = 100
    """The falls remembered to restart from: those of the last this-many fresh episodes that
    fell (a restarted episode's fall is not remembered, so one hard spot cannot crowd out the
    others)."""
    fall_restart_start: int = 0
    """Policy step after which episodes may restart, and falls are remembered."""
    fall_restart_probe: float = 0.0
    """The probability that a fresh episode (after ``fall_restart_start``) is a probe: played by
    the deterministic policy, the one evaluations score, and stored like any other. Above 0,
    only probes' falls are remembered, so restarts rebuild the falls that cost evaluations and
    explore (with the stochastic policy) a little before them. 0: every fresh episode is
    stochastic and any fresh fall is remembered."""
    refill_steps: int = 50_000
    """A run continued from a ``restart.pt`` (no replay buffer: ``bipedal resume FILE --into
    DIR``) first acts this many policy steps with its own actor, without updates, to refill the
    buffer it lost; then learning goes on. Changes nothing in a run that is not restarted."""


@dataclass
class CurriculumConfig:
    """``bipedal curriculum``: BipedalWalker-v3 first, then BipedalWalkerHardcore-v3."""

    walker_steps: int = 300_000
    """Stage 1 budget: env steps on BipedalWalker-v3 (it ends earlier once solved)."""
    hardcore_steps: int = 3_000_000
    """Stage 2 budget: env steps on BipedalWalkerHardcore-v3 (ends earlier once solved)."""
    replay: str = "keep"
    """At the switch: keep the Walker transitions in the replay buffer, or clear it."""


@dataclass
class Config:
    """Everything a run needs; one YAML file fills it."""

    env: str = "BipedalWalker-v3"
    """Gymnasium id (or alias walker / hardcore)."""
    seed: int = 0
    """Seeds networks, exploration, replay sampling and env resets."""
    device: str = "auto"
    """auto, cpu or cuda."""
    agent: AgentConfig = field(default_factory=AgentConfig)
    train: TrainConfig = field(default_factory=TrainConfig)
    curriculum: CurriculumConfig = field(default_factory=CurriculumConfig)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


def config_from_dict(data: dict[str, Any], source: str = "config") -> Config:
    cfg = Config()
    fill_dataclass(cfg, data or {}, source)
    cfg.env = canonical_env_id(cfg.env, f"{source}: key 'env'")
    validate(cfg, source)  # the range of every value (validation.py)
    return cfg


def resolve_config(
    config_path: str | Path | None = None,
    overrides: list[str] | None = None,
    **explicit: Any,
) -> Config:
    """YAML file, then ``--set`` overrides, then explicit CLI options that are not None.

    ``explicit`` maps dotted keys (``'train.total_steps'``) to values from dedicated options.
    """
    data: dict[str, Any] = load_yaml(config_path) if config_path else {}
    return override_config(
        data, str(config_path) if config_path else "config", overrides, **explicit
    )


def override_config(
    data: dict[str, Any], source: str, overrides: list[str] | None = None, **explicit: Any
) -> Config:
    """``data`` (a config as a dict, named ``source`` in errors) with ``--set`` overrides, then
    explicit CLI options that are not None, resolved."""
    data = copy.deepcopy(data)
    for text in overrides or []:
        path, value = parse_override(text)
        set_nested(data, path, value)
        source = f"{source} + --set" if "--set" not in source else source
    for dotted, value in explicit.items():
        if value is not None:
            set_nested(data, dotted.split("."), value)
    return config_from_dict(data, source)
