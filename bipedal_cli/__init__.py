"""bipedal: TQC + D2RL agents for Gymnasium's BipedalWalker environments.

The library is usable without the CLI::

    from bipedal_cli import Config, train
    result = train(Config(), run_dir="runs/demo")
"""

from .config import AgentConfig, Config, TrainConfig, resolve_config
from .errors import UserError

__all__ = ["AgentConfig", "Config", "TrainConfig", "UserError", "resolve_config"]
__version__ = "0.1.0"
