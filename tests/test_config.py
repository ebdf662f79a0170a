from pathlib import Path

import pytest

from bipedal_cli.config import Config, config_from_dict, parse_override, resolve_config
from bipedal_cli.errors import UserError

CONFIGS = Path(__file__).resolve().parent.parent / "configs"


def test_default_yaml_equals_the_dataclass_defaults():
    assert resolve_config(CONFIGS / "walker.yaml") == Config()


@pytest.mark.parametrize("name", ["walker", "paper", "hardcore", "mlp-ablation", "curriculum"])
def test_shipped_configs_load(name):
    path = CONFIGS / f"{name}.yaml"
    if not path.exists():
        pytest.skip(f"{path.name} not shipped")
    resolve_config(path)


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
