from pathlib import Path

import numpy as np
import pytest

from bipedal_cli.config import (
    Config,
    TrainConfig,
    config_from_dict,
    parse_override,
    resolve_config,
)
from bipedal_cli.errors import UserError
from bipedal_cli.fall_restarts import draws_probe, restarts_on
from bipedal_cli.schedule import batch_size_at, updates_at

CONFIGS = Path(__file__).resolve().parent.parent / "configs"
ROOT = CONFIGS.parent


def test_default_yaml_equals_the_dataclass_defaults():
    assert resolve_config(CONFIGS / "walker.yaml") == Config()


# Hardcore, D2RL, action repeat 3, history 4, 3-step returns, fall penalty -5, rewards x5
HARDCORE_H4 = ("BipedalWalkerHardcore-v3", True, 3, 4, 3, -5.0, 5.0)
SHIPPED = {
    # name: (env, d2rl, action_repeat, history, n_step, fall_penalty, reward_scale)
    "walker": ("BipedalWalker-v3", True, 1, 1, 1, None, 1.0),
    "paper": ("BipedalWalker-v3", True, 1, 1, 1, None, 1.0),
    "mlp-ablation": ("BipedalWalker-v3", False, 1, 1, 1, None, 1.0),
    "curriculum": ("BipedalWalker-v3", True, 1, 1, 1, None, 1.0),
    "hardcore": HARDCORE_H4,
    "hardcore-curriculum": ("BipedalWalker-v3", True, 3, 4, 3, -5.0, 5.0),
    "hardcore-lrdecay": HARDCORE_H4,
    "hardcore-h8-curated": ("BipedalWalkerHardcore-v3", True, 3, 8, 3, -5.0, 5.0),
    "hardcore-h8-fallramp": ("BipedalWalkerHardcore-v3", True, 3, 8, 3, -5.0, 5.0),
    "hardcore-lrdecay-cvar": HARDCORE_H4,
    "hardcore-lrdecay-cvar-late": HARDCORE_H4,
    "hardcore-lrdecay-cvar25": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-g99": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-g99-b256": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-g99-restarts": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-g99-probes": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-g99-probes-late": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-g99-utd2": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-wide": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-ar2": ("BipedalWalkerHardcore-v3", True, 2, 6, 4, -5.0, 5.0),
    "hardcore-lrdecay-cvar25-ere": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-ere-stumps": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-stumps": HARDCORE_H4,
    "hardcore-lrdecay-cvar10-ere": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-buffer2m": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-buffer2m-stumps4": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-smooth": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-entropy8": HARDCORE_H4,
    "hardcore-lrdecay-cvar25-drop4": HARDCORE_H4,
    "hardcore-lstm12": HARDCORE_H4[:3] + (12,) + HARDCORE_H4[4:],
    "hardcore-warm-anchor100": HARDCORE_H4,
    "hardcore-warm-anchor25": HARDCORE_H4,
    "hardcore-warm-kl100": HARDCORE_H4,
    "hardcore-warm-kl20": HARDCORE_H4,
    "hardcore-warm-kl100-fall25": HARDCORE_H4,
    "hardcore-warm-kl100-fall100": HARDCORE_H4,
    "hardcore-warm-kl100-c10": HARDCORE_H4,
}


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_shipped_configs_load_with_the_settings_their_comments_describe(name):
    cfg = resolve_config(CONFIGS / f"{name}.yaml")
    a, t = cfg.agent, cfg.train
    got = (cfg.env, a.d2rl, a.action_repeat, a.history, a.n_step, t.fall_penalty, t.reward_scale)
    assert got == SHIPPED[name]
    assert config_from_dict(cfg.to_dict()) == cfg  # what a run writes reads back the same


def test_every_shipped_config_is_tested():
    assert {p.stem for p in CONFIGS.glob("*.yaml")} == set(SHIPPED)


def test_hardcore_lrdecay_is_hardcore_until_its_decay_starts():
    """It was trained as a branch of hardcore.yaml's run at step 1,092,168 (docs/hardcore.md)."""
    from bipedal_cli.branch_rules import check_branch_config

    base, decay = (resolve_config(CONFIGS / f"{n}.yaml") for n in ("hardcore", "hardcore-lrdecay"))
    assert base.agent.lr_final is None
    a = decay.agent
    assert (a.lr_final, a.lr_decay_start, a.lr_decay_end) == (7.3e-5, 1_100_000, 1_700_000)
    check_branch_config(base, decay, 1_092_168, "hardcore-lrdecay.yaml")
    with pytest.raises(UserError, match="lr_decay_start"):
        check_branch_config(base, decay, 1_100_001, "hardcore-lrdecay.yaml")


def test_hardcore_h8_curated_is_lrdecay_with_history_8_and_fork_curation():
    """Its comparison from step 0 is hardcore-lrdecay.yaml's run: nothing else may differ."""
    decay, h8 = (
        resolve_config(CONFIGS / f"{n}.yaml") for n in ("hardcore-lrdecay", "hardcore-h8-curated")
    )
    assert (h8.agent.history, h8.train.replay_keep_below, h8.train.replay_curation_start) == (
        8,
        250.0,
        0,
    )
    assert h8.train.keep_policies
    h8.agent.history, h8.train.replay_keep_below, h8.train.keep_policies = 4, None, False
    assert h8 == decay


def test_hardcore_h8_fallramp_is_h8_curated_until_its_ramp_starts():
    """It branches from hardcore-h8-curated.yaml's run: nothing but the ramp may differ."""
    h8, ramp = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-h8-curated", "hardcore-h8-fallramp")
    )
    t = ramp.train
    assert (t.fall_penalty_final, t.fall_penalty_ramp_start, t.fall_penalty_ramp_end) == (
        -30.0,
        1_280_000,
        1_380_000,
    )
    t.fall_penalty_final, t.fall_penalty_ramp_start, t.fall_penalty_ramp_end = None, 0, 0
    assert ramp == h8


def test_hardcore_lrdecay_cvar_is_lrdecay_until_its_actor_turns_risk_averse():
    """It branches from hardcore-lrdecay.yaml's runs at 1.1M: nothing but the actor's objective
    may differ, and the branch check accepts it from a run at that step."""
    from bipedal_cli.branch_rules import check_branch_config
    from bipedal_cli.schedule import actor_lowest_atoms

    decay, cvar = (
        resolve_config(CONFIGS / f"{n}.yaml") for n in ("hardcore-lrdecay", "hardcore-lrdecay-cvar")
    )
    assert (cvar.agent.actor_cvar, cvar.agent.actor_cvar_start) == (0.5, 1_100_000)
    assert actor_lowest_atoms(1_100_001, cvar.agent) == 63  # of 125
    check_branch_config(decay, cvar, 1_100_000, "hardcore-lrdecay-cvar.yaml")
    cvar.agent.actor_cvar, cvar.agent.actor_cvar_start = None, 0
    assert cvar == decay


def test_hardcore_lrdecay_cvar25_is_seed_1s_decaying_run_until_its_actor_turns_risk_averse():
    """Session 11's branch: seed 1's run of hardcore-lrdecay.yaml at 1.1M, with the lowest
    quarter of the atoms from there; nothing else may differ, and the branch check accepts it
    from that run at 1.1M but not from a step past it."""
    from bipedal_cli.branch_rules import check_branch_config
    from bipedal_cli.errors import UserError
    from bipedal_cli.schedule import actor_lowest_atoms

    decay, cvar = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-lrdecay", "hardcore-lrdecay-cvar25")
    )
    decay.seed, decay.train.keep_policies = 1, True  # the seed-1 run's own config
    assert (cvar.seed, cvar.agent.actor_cvar, cvar.agent.actor_cvar_start) == (1, 0.25, 1_100_000)
    assert actor_lowest_atoms(1_100_000, cvar.agent) is None  # eq. 2 up to the branch point
    assert actor_lowest_atoms(1_100_001, cvar.agent) == 31  # then 31 of 125
    check_branch_config(decay, cvar, 1_100_000, "hardcore-lrdecay-cvar25.yaml")
    with pytest.raises(UserError, match="actor_cvar_start"):
        check_branch_config(decay, cvar, 1_100_001, "hardcore-lrdecay-cvar25.yaml")
    cvar.agent.actor_cvar, cvar.agent.actor_cvar_start = None, 0
    assert cvar == decay


def test_hardcore_lrdecay_cvar25_g99_is_its_seed_0_run_but_for_the_discount():
    """Session 16's run from scratch: hardcore-lrdecay-cvar25.yaml's seed-0 run (committed
    metrics to 1,779,687) with gamma 0.99 per policy step; nothing else may differ."""
    cvar, g99 = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-lrdecay-cvar25", "hardcore-lrdecay-cvar25-g99")
    )
    assert (g99.seed, g99.agent.gamma, cvar.agent.gamma) == (0, 0.99, 0.98)
    g99.seed, g99.agent.gamma = 1, 0.98
    assert g99 == cvar


def test_hardcore_lrdecay_cvar25_wide_is_its_seed_0_run_but_for_the_critics_width():
    """Session 27's run from scratch: hardcore-lrdecay-cvar25.yaml's seed-0 run with critics
    of 512 units per hidden layer instead of 256; nothing else may differ."""
    cvar, wide = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-lrdecay-cvar25", "hardcore-lrdecay-cvar25-wide")
    )
    assert (wide.seed, wide.agent.critic_hidden, cvar.agent.critic_hidden) == (0, 512, 256)
    assert wide.agent.actor_hidden == 512
    wide.seed, wide.agent.critic_hidden = 1, 256
    assert wide == cvar


def test_hardcore_lstm12_is_its_seed_0_run_but_for_the_window_and_its_lstm():
    """Session 38's run from scratch: hardcore-lrdecay-cvar25.yaml's seed-0 run with 12
    observations read by an LSTM of width 64 instead of 4 flat ones; nothing else may differ."""
    cvar, lstm = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-lrdecay-cvar25", "hardcore-lstm12")
    )
    a = lstm.agent
    assert (lstm.seed, a.history, a.encoder, a.encoder_hidden) == (0, 12, "lstm", 64)
    assert cvar.agent.encoder == "none"
    lstm.seed, a.history, a.encoder = 1, 4, "none"
    assert lstm == cvar  # encoder_hidden is 64 in both: it is read only with an encoder


def test_hardcore_lrdecay_cvar25_ar2_is_its_seed_0_run_per_env_step_at_action_repeat_2():
    """Session 40's run from scratch: hardcore-lrdecay-cvar25.yaml's seed-0 run with each action
    held for 2 env steps instead of 3. What spans env steps keeps its span (the discount per env
    step, the window, the n-step horizon within one env step, and every schedule at 1.5 times
    the policy steps); what counts updates keeps its count; nothing else may differ."""
    cvar, ar2 = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-lrdecay-cvar25", "hardcore-lrdecay-cvar25-ar2")
    )
    a, b = ar2.agent, cvar.agent
    assert (ar2.seed, a.action_repeat, b.action_repeat) == (0, 2, 3)
    assert a.gamma ** (1 / 2) == pytest.approx(b.gamma ** (1 / 3), abs=1e-5)
    assert a.history * 2 == b.history * 3 == 12
    assert abs(a.n_step * 2 - b.n_step * 3) == 1
    spans = [(a, b, n) for n in ("lr_decay_start", "lr_decay_end", "actor_cvar_start")]
    spans += [
        (ar2.train, cvar.train, n)
        for n in ("total_steps", "warmup_steps", "buffer_size", "eval_every", "checkpoint_every")
    ]
    for mine, theirs, name in spans:  # the same env steps at 1.5 times the policy steps
        assert getattr(mine, name) * 2 == getattr(theirs, name) * 3, name
        setattr(mine, name, getattr(theirs, name))
    ar2.seed = 1
    a.action_repeat, a.gamma, a.history, a.n_step = 3, b.gamma, b.history, b.n_step
    assert ar2 == cvar


def test_hardcore_lrdecay_cvar25_ere_is_its_seed_0_run_with_recent_experience_emphasized():
    """Session 45's run from scratch: the seed-0 run of hardcore-lrdecay-cvar25.yaml (the shipped
    policy's, its config in docs/runs) with ERE, eta 0.996 annealed to 1 at the decay's end;
    nothing else may differ."""
    from bipedal_cli.recency import recency_at

    seed0 = resolve_config(ROOT / "docs/runs/hardcore-lrdecay-cvar25-seed0/config.yaml")
    ere = resolve_config(CONFIGS / "hardcore-lrdecay-cvar25-ere.yaml")
    t = ere.train
    assert (t.replay_recency, t.replay_recency_end, t.replay_recent_min) == (0.996, 1_700_000, 5000)
    assert t.replay_recency_end == ere.agent.lr_decay_end
    assert recency_at(1_700_000, t) == 1.0 and recency_at(0, seed0.train) is None
    t.replay_recency, t.replay_recency_end = None, None
    assert ere == seed0


def test_hardcore_lrdecay_cvar25_stumps_is_its_seed_0_run_with_twice_the_stumps():
    """Prepared in session 45: the seed-0 run of hardcore-lrdecay-cvar25.yaml with stumps
    weighted 2 against 1 for stairs and pits from the first episode; nothing else may differ."""
    from bipedal_cli.episodes import obstacle_mix_on

    seed0 = resolve_config(ROOT / "docs/runs/hardcore-lrdecay-cvar25-seed0/config.yaml")
    stumps = resolve_config(CONFIGS / "hardcore-lrdecay-cvar25-stumps.yaml")
    t = stumps.train
    assert (t.obstacle_stump, t.obstacle_stairs, t.obstacle_pit) == (2.0, 1.0, 1.0)
    assert obstacle_mix_on(t, 0) and not obstacle_mix_on(seed0.train, 10**7)
    t.obstacle_stump = 1.0
    assert stumps == seed0


def test_the_ere_stumps_config_is_the_ere_run_branched_at_1_1m_with_twice_the_stumps():
    """Session 46's branch: the ERE run from its full state at 1.1M, with stumps weighted 2
    against 1 from there. The branch check accepts it at 1.1M, not a step later, and nothing but
    the obstacle weights differs."""
    from bipedal_cli.branch_rules import check_branch_config
    from bipedal_cli.episodes import obstacle_mix_on

    ere, stumps = (
        resolve_config(CONFIGS / f"hardcore-lrdecay-cvar25-{n}.yaml") for n in ("ere", "ere-stumps")
    )
    t = stumps.train
    assert (t.obstacle_stump, t.obstacle_stairs, t.obstacle_pit) == (2.0, 1.0, 1.0)
    assert not obstacle_mix_on(t, 1_099_999) and obstacle_mix_on(t, 1_100_000)
    check_branch_config(ere, stumps, 1_100_000, "hardcore-lrdecay-cvar25-ere-stumps.yaml")
    with pytest.raises(UserError, match="obstacle_mix_start"):
        check_branch_config(ere, stumps, 1_100_001, "hardcore-lrdecay-cvar25-ere-stumps.yaml")
    t.obstacle_stump, t.obstacle_mix_start = 1.0, TrainConfig().obstacle_mix_start
    assert stumps == ere


def test_the_cvar10_ere_config_is_the_ere_run_branched_at_1_1m_with_c_0_1():
    """Session 47's branch: the ERE run from its full state at 1.1M, with the actor maximising the
    lowest tenth of the atoms instead of the lowest quarter from there. The branch check accepts
    it at 1.1M, not a step later, and nothing but c differs."""
    from bipedal_cli.branch_rules import check_branch_config

    ere, c10 = (
        resolve_config(CONFIGS / f"hardcore-lrdecay-{n}.yaml") for n in ("cvar25-ere", "cvar10-ere")
    )
    assert (c10.agent.actor_cvar, c10.agent.actor_cvar_start) == (0.1, 1_100_000)
    check_branch_config(ere, c10, 1_100_000, "hardcore-lrdecay-cvar10-ere.yaml")
    with pytest.raises(UserError, match="actor_cvar"):
        check_branch_config(ere, c10, 1_100_001, "hardcore-lrdecay-cvar10-ere.yaml")
    c10.agent.actor_cvar = 0.25
    assert c10 == ere


def test_the_buffer2m_config_is_its_seed_0_run_with_a_buffer_that_never_wraps_before_2m():
    """Session 48's run from scratch: the seed-0 run of hardcore-lrdecay-cvar25.yaml with a
    replay buffer of 2M transitions, more than the run stores to the end of its decay; nothing
    else may differ."""
    from bipedal_cli.branch_rules import check_branch_config

    seed0 = resolve_config(ROOT / "docs/runs/hardcore-lrdecay-cvar25-seed0/config.yaml")
    big = resolve_config(CONFIGS / "hardcore-lrdecay-cvar25-buffer2m.yaml")
    assert big.train.buffer_size == 2_000_000 > big.agent.lr_decay_end
    # its control: its state at 1M branched to seed 0's 1M buffer, while nothing has wrapped
    held = {"capacity": 2_000_000, "size": 999_999, "pos": 999_999}
    check_branch_config(big, seed0, 1_000_000, "--set", held)
    with pytest.raises(UserError, match="train.buffer_size"):
        check_branch_config(
            big, seed0, 1_000_002, "--set", held | {"size": 1_000_001, "pos": 1_000_001}
        )
    big.train.buffer_size = 1_000_000
    assert big == seed0


def test_the_buffer2m_stumps4_config_is_the_2m_run_branched_at_1m_with_four_times_the_stumps():
    """Session 55's branch: the 2M-buffer run from its full state at 1M, with stumps weighted 4
    against 1 from there. The branch check accepts it at 1M, not a step later, and nothing but
    the obstacle weights differs."""
    from bipedal_cli.branch_rules import check_branch_config
    from bipedal_cli.episodes import obstacle_mix_on

    big, stumps = (
        resolve_config(CONFIGS / f"hardcore-lrdecay-cvar25-{n}.yaml")
        for n in ("buffer2m", "buffer2m-stumps4")
    )
    t = stumps.train
    assert (t.obstacle_stump, t.obstacle_stairs, t.obstacle_pit) == (4.0, 1.0, 1.0)
    assert not obstacle_mix_on(t, 999_999) and obstacle_mix_on(t, 1_000_000)
    name = "hardcore-lrdecay-cvar25-buffer2m-stumps4.yaml"
    check_branch_config(big, stumps, 1_000_000, name)
    with pytest.raises(UserError, match="obstacle_mix_start"):
        check_branch_config(big, stumps, 1_000_001, name)
    t.obstacle_stump, t.obstacle_mix_start = 1.0, TrainConfig().obstacle_mix_start
    assert stumps == big


# session 49's candidates: (their agent keys from 1.1M, the key the branch check names)
LATE_CANDIDATES = {
    "smooth": (
        {"actor_smooth": 1.0, "actor_smooth_sigma": 0.01, "actor_smooth_start": 1_100_000},
        "actor_smooth_start",
    ),
    "entropy8": (
        {
            "target_entropy_final": -8.0,
            "target_entropy_decay_start": 1_100_000,
            "target_entropy_decay_end": 1_700_000,
        },
        "target_entropy_decay_start",
    ),
    "drop4": (
        {"drop_per_critic_final": 4, "drop_per_critic_start": 1_100_000},
        "drop_per_critic_start",
    ),
}


@pytest.mark.parametrize("name", sorted(LATE_CANDIDATES))
def test_the_late_candidates_are_seed_0s_run_branched_from_the_2m_run_at_1m(name):
    """Session 49's candidates: the 2M-buffer run's state at 1M, branched to the 1M buffer with
    one feature that starts at 1.1M. The branch check accepts each there and from the control's
    state at 1.1M, not a step later, and nothing but the feature's keys differs from seed 0's
    run."""
    from dataclasses import fields

    from bipedal_cli.branch_rules import check_branch_config
    from bipedal_cli.config import AgentConfig

    keys, start_key = LATE_CANDIDATES[name]
    seed0 = resolve_config(ROOT / "docs/runs/hardcore-lrdecay-cvar25-seed0/config.yaml")
    big = resolve_config(CONFIGS / "hardcore-lrdecay-cvar25-buffer2m.yaml")
    cfg = resolve_config(CONFIGS / f"hardcore-lrdecay-cvar25-{name}.yaml")
    assert {k: getattr(cfg.agent, k) for k in keys} == keys
    held = {"capacity": 2_000_000, "size": 999_999, "pos": 999_999}
    source = f"hardcore-lrdecay-cvar25-{name}.yaml"
    check_branch_config(big, cfg, 1_000_000, source, held)
    check_branch_config(seed0, cfg, 1_100_000, source)  # or from the control at 1.1M
    with pytest.raises(UserError, match=start_key):
        check_branch_config(seed0, cfg, 1_100_001, source)
    defaults = {f.name: getattr(AgentConfig(), f.name) for f in fields(AgentConfig)}
    for key in keys:
        setattr(cfg.agent, key, defaults[key])
    assert cfg == seed0


RESTART_KEYS = tuple(
    f"train.fall_restart{s}" for s in ("", "_back", "_back_min", "_horizon", "_memory", "_start")
)
G99_BRANCHES = {
    # config: (branch step, the key that starts it, the keys it changes, what it does from there)
    "hardcore-lrdecay-cvar25-g99-b256": (
        1_944_373,
        "batch_size_start",
        ("agent.batch_size_final", "agent.batch_size_start"),
        lambda c, s: batch_size_at(s, c.agent),
        (64, 256),
    ),
    "hardcore-lrdecay-cvar25-g99-restarts": (
        1_944_373,
        "fall_restart_start",
        RESTART_KEYS,
        lambda c, s: restarts_on(c.train, s),
        (False, True),
    ),
    "hardcore-lrdecay-cvar25-g99-probes": (
        1_944_373,
        "fall_restart_start",
        (*RESTART_KEYS, "train.fall_restart_probe"),
        lambda c, s: draws_probe(np.random.default_rng(0), c.train, s),
        (False, True),
    ),
    "hardcore-lrdecay-cvar25-g99-probes-late": (
        2_157_722,  # session 24's control, restarted from the restart file
        "fall_restart_start",
        (*RESTART_KEYS, "train.fall_restart_probe"),
        lambda c, s: draws_probe(np.random.default_rng(0), c.train, s),
        (False, True),
    ),
    "hardcore-lrdecay-cvar25-g99-utd2": (
        2_464_591,  # session 25's control, where it stopped
        "updates_per_step_start",
        ("train.updates_per_step_final", "train.updates_per_step_start"),
        lambda c, s: updates_at(s, c.train),
        (1, 2),
    ),
}


@pytest.mark.parametrize("name", sorted(G99_BRANCHES))
def test_the_gamma_099_branches_are_that_run_until_their_branch_step(name):
    """Sessions 21-25's branches: the gamma-0.99 run where a session stopped it, with one
    feature from the next step; nothing else may differ, and the branch check accepts each from
    that run at its branch step but not from a step past it."""
    from bipedal_cli.branch_rules import check_branch_config

    step, start_key, keys, feature, expected = G99_BRANCHES[name]
    g99, new = (
        resolve_config(CONFIGS / f"{n}.yaml") for n in ("hardcore-lrdecay-cvar25-g99", name)
    )
    assert tuple(feature(new, s) for s in (step, step + 1)) == expected
    check_branch_config(g99, new, step, f"{name}.yaml")
    with pytest.raises(UserError, match=start_key):
        check_branch_config(g99, new, step + 1, f"{name}.yaml")
    plain = Config()
    for key in keys:
        section, field = key.split(".")
        setattr(getattr(new, section), field, getattr(getattr(plain, section), field))
    assert new == g99


def test_the_probes_config_is_the_restarts_config_but_for_its_probes():
    """Session 23 changes one thing against session 22: where the remembered falls come from."""
    probes, restarts = (
        resolve_config(CONFIGS / f"hardcore-lrdecay-cvar25-g99-{n}.yaml")
        for n in ("probes", "restarts")
    )
    assert probes.train.fall_restart_probe == 1.0
    probes.train.fall_restart_probe = TrainConfig().fall_restart_probe
    assert probes == restarts


def test_the_late_probes_config_is_the_probes_config_but_for_its_start():
    """Session 24's next step: the same probes, from the control restarted from the restart file."""
    late, probes = (
        resolve_config(CONFIGS / f"hardcore-lrdecay-cvar25-g99-{n}.yaml")
        for n in ("probes-late", "probes")
    )
    starts = (late.train.fall_restart_start, probes.train.fall_restart_start)
    assert starts == (2_157_722, 1_944_373)
    late.train.fall_restart_start = probes.train.fall_restart_start
    assert late == probes


def test_hardcore_lrdecay_cvar_late_is_the_branch_of_the_decaying_run_at_1_728_282():
    """The pilot: seed 0's decaying run, branched where it stood when the key was added."""
    from bipedal_cli.branch_rules import check_branch_config

    decay, late = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-lrdecay", "hardcore-lrdecay-cvar-late")
    )
    assert (late.agent.actor_cvar, late.agent.actor_cvar_start) == (0.5, 1_730_000)
    check_branch_config(decay, late, 1_728_282, "hardcore-lrdecay-cvar-late.yaml")
    late.agent.actor_cvar, late.agent.actor_cvar_start, late.train.keep_policies = None, 0, False
    assert late == decay


@pytest.mark.parametrize(
    "name,anchor", [("hardcore-warm-anchor100", 100.0), ("hardcore-warm-anchor25", 25.0)]
)
def test_hardcore_warm_configs_are_lrdecay_from_the_committed_parent(name, anchor):
    """A new run from the shipped-until-session-9 policy: its parent file is committed and is the
    one the config pins; the rest is hardcore-lrdecay.yaml but for the schedule its comments
    give and the anchor of its name."""
    import hashlib

    from bipedal_cli.checkpoint import initial_actor_state

    decay, warm = (resolve_config(CONFIGS / f"{n}.yaml") for n in ("hardcore-lrdecay", name))
    a, t = warm.agent, warm.train
    root = CONFIGS.parent
    assert hashlib.sha256((root / t.init_policy).read_bytes()).hexdigest() == t.init_policy_sha256
    t.init_policy = str(root / t.init_policy)
    assert initial_actor_state(warm, 96, 4)  # it fits this config
    assert (a.actor_anchor, a.lr_decay_start, a.lr_decay_end, a.actor_update_start) == (
        anchor,
        30_000,
        60_000,
        60_000,
    )
    assert (a.actor_cvar, a.actor_cvar_start, a.init_alpha, t.total_steps) == (
        0.25,
        0,
        0.137,
        1_000_000,
    )
    a.actor_anchor, a.lr_decay_start, a.lr_decay_end, a.actor_update_start = (
        None,
        1_100_000,
        1_700_000,
        0,
    )
    a.actor_cvar, a.init_alpha, t.total_steps = None, 1.0, 3_000_000
    t.init_policy = t.init_policy_sha256 = None
    t.keep_policies = False
    assert warm == decay


@pytest.mark.parametrize("beta", [100.0, 20.0])
def test_hardcore_warm_kl_configs_are_branches_of_the_anchor25_run_at_its_actor_start(beta):
    """Made as branches of hardcore-warm-anchor25.yaml's run at 60,000, where the actor starts:
    the branch check accepts them there, and nothing but the anchor differs."""
    from bipedal_cli.branch_rules import check_branch_config

    a25 = resolve_config(CONFIGS / "hardcore-warm-anchor25.yaml")
    kl = resolve_config(CONFIGS / f"hardcore-warm-kl{beta:.0f}.yaml")
    check_branch_config(a25, kl, 60_000, "kl")
    with pytest.raises(UserError, match="actor_update_start"):
        check_branch_config(a25, kl, 60_001, "kl")
    assert (kl.agent.actor_anchor, kl.agent.actor_anchor_kl) == (None, beta)
    kl.agent.actor_anchor, kl.agent.actor_anchor_kl = 25.0, None
    assert kl == a25


@pytest.mark.parametrize("final", [25.0, 100.0])
def test_hardcore_warm_kl100_fall_configs_are_branches_of_the_kl100_run(final):
    """Made as branches of hardcore-warm-kl100.yaml's run at 325,163 (session 10): the branch
    check accepts them there, not after the ramp has started, and nothing but the ramp differs."""
    from bipedal_cli.branch_rules import check_branch_config

    kl = resolve_config(CONFIGS / "hardcore-warm-kl100.yaml")
    ramp = resolve_config(CONFIGS / f"hardcore-warm-kl100-fall{final:.0f}.yaml")
    check_branch_config(kl, ramp, 325_163, "fall")
    with pytest.raises(UserError, match="fall_penalty_ramp_start"):
        check_branch_config(kl, ramp, 326_001, "fall")
    t = ramp.train
    assert (t.fall_penalty_final, t.fall_penalty_ramp_start, t.fall_penalty_ramp_end) == (
        -final,
        326_000,
        346_000,
    )
    t.fall_penalty_final, t.fall_penalty_ramp_start, t.fall_penalty_ramp_end = None, 0, 0
    assert ramp == kl


def test_hardcore_warm_kl100_c10_is_kl100_but_for_the_actors_objective():
    """Session 10's run from the same parent: only the share of atoms the actor maximises."""
    kl, c10 = (
        resolve_config(CONFIGS / f"{n}.yaml")
        for n in ("hardcore-warm-kl100", "hardcore-warm-kl100-c10")
    )
    assert (c10.agent.actor_cvar, kl.agent.actor_cvar) == (0.1, 0.25)
    c10.agent.actor_cvar = 0.25
    assert c10 == kl


def test_paper_config_is_the_default_but_for_the_learning_rate():
    paper, walker = resolve_config(CONFIGS / "paper.yaml"), Config()
    assert paper.agent.lr == pytest.approx(3.296e-4) and walker.agent.lr == 7.3e-4
    paper.agent.lr = walker.agent.lr
    assert paper == walker


def test_paper_config_is_table1_modes_and_mean_learning_rate():
    cfg = resolve_config(CONFIGS / "paper.yaml")
    lrs = [0.000302, 0.0003, 0.000465, 0.000273, 0.000308]
    assert cfg.agent.lr == pytest.approx(sum(lrs) / 5)
    assert (cfg.agent.gamma, cfg.agent.batch_size, cfg.train.buffer_size) == (0.98, 64, 1_000_000)
    assert (cfg.agent.n_critics, cfg.agent.n_quantiles, cfg.train.warmup_steps) == (5, 25, 1000)


def test_precedence_set_over_yaml_over_defaults(tmp_path):
    path = tmp_path / "c.yaml"
    path.write_text("agent:\n  lr: 0.002\n  batch_size: 32\n")
    cfg = resolve_config(path, ["agent.lr=1e-4"], **{"train.total_steps": 5})
    assert cfg.agent.lr == 1e-4 and cfg.agent.batch_size == 32 and cfg.train.total_steps == 5
    assert cfg.agent.gamma == 0.98


def test_env_aliases_and_errors_name_the_key():
    assert config_from_dict({"env": "hardcore"}).env == "BipedalWalkerHardcore-v3"
    with pytest.raises(UserError, match="'agent.gama'"):
        config_from_dict({"agent": {"gama": 0.9}})
    with pytest.raises(UserError, match="'train.total_steps'.*int"):
        config_from_dict({"train": {"total_steps": "many"}})
    with pytest.raises(UserError, match="'agent.d2rl'.*bool"):
        config_from_dict({"agent": {"d2rl": 1}})
    with pytest.raises(UserError, match="'curriculum.replay'.*keep or clear"):
        config_from_dict({"curriculum": {"replay": "maybe"}})
    with pytest.raises(UserError, match="drop_per_critic"):
        config_from_dict({"agent": {"drop_per_critic": 25}})


def test_override_parsing():
    assert parse_override("agent.lr=3e-4") == (["agent", "lr"], 3e-4)
    assert parse_override("agent.d2rl=false") == (["agent", "d2rl"], False)
    assert parse_override("agent.target_entropy=null") == (["agent", "target_entropy"], None)
