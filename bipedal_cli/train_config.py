"""The training loop's section of a config: budget, replay, evaluation and checkpoints, and what
the learner sees (shaping, curation, obstacle mix, restarts near falls), as a typed dataclass
(:mod:`bipedal_cli.config` fills it)."""

from __future__ import annotations

from dataclasses import dataclass, field


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
    obstacle_stump: float = 1.0
    """Training only: the weight of stumps among Hardcore's obstacles on the learner's courses;
    with ``obstacle_stairs`` and ``obstacle_pit`` the kinds are drawn in proportion (equal
    weights: the unmodified env's 1/3 each; :mod:`~bipedal_cli.obstacle_mix`). Evaluations
    always play the unmodified env."""
    obstacle_stairs: float = 1.0
    """Training only: the weight of staircases (see ``obstacle_stump``)."""
    obstacle_pit: float = 1.0
    """Training only: the weight of pits (see ``obstacle_stump``)."""
    obstacle_mix_start: int = 0
    """Policy step from which episodes (those that start there or later) train on the mix."""
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
    refill_policies: list[str] = field(default_factory=list)
    """Policy files the refill acts with instead of the restart's own actor, one per episode in
    turn (episode e by file e mod K), each sampling from its own Gaussian with the run's noise:
    a mixture of earlier policies, as a run's own buffer holds. They must have this config's
    action repeat, history and actor shape. Empty: the restart's own actor."""

    def obstacle_weights(self) -> tuple[float, float, float]:
        """The weights of stump, stairs and pit (``obstacle_stump``, ``_stairs``, ``_pit``)."""
        return (self.obstacle_stump, self.obstacle_stairs, self.obstacle_pit)

    def mixes_obstacles(self) -> bool:
        """Unequal weights: courses with a mix of obstacles from ``obstacle_mix_start`` (equal
        weights are the unmodified env: no wrapper at all, so the bits stay the env's)."""
        return len(set(self.obstacle_weights())) > 1
