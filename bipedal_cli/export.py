"""A standalone policy file: ``torch.export`` of the deterministic actor, usable with torch alone.

    policy = torch.export.load("policy.pt2").module()
    actions = policy(obs)          # obs: (B, 24) float32 -> actions: (B, 4) in [-1, 1]

A policy with an observation history of H > 1 takes its last H observations, oldest first:
obs (B, H, 24). A policy with action repeat k > 1 expects each action to be held for k env
steps. Both are also in the file's ``bipedal.json`` (``torch.export.load(path,
extra_files={"bipedal.json": ""})``). TorchScript is deprecated in current torch;
``torch.export`` is its replacement. The exported program holds the weights and the graph, not
our Python code, so loading needs nothing of this package.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import torch

from .paths import atomic_path

EXPORT_SUFFIXES = (".pt2", ".pt")
META_FILE = "bipedal.json"


class _HistoryPolicy(torch.nn.Module):
    """(B, H, obs) -> (B, act): the H observations flattened, oldest first, as in training."""

    def __init__(self, actor: torch.nn.Module) -> None:
        super().__init__()
        self.actor = actor

    def forward(self, obs: torch.Tensor) -> torch.Tensor:
        return self.actor.deterministic(obs.flatten(1))


def input_shape(obs_dim: int, history: int) -> tuple[int, ...]:
    """The exported program's input shape after the batch dimension."""
    return (obs_dim,) if history == 1 else (history, obs_dim // history)


def export_policy(
    actor: torch.nn.Module, out: Path, history: int = 1, action_repeat: int = 1, batch_hint=8
) -> None:
    """Export ``actor.deterministic`` with a dynamic batch dimension and save it to ``out``."""
    actor = actor.cpu().eval()
    module = actor if history == 1 else _HistoryPolicy(actor)
    example = torch.zeros(batch_hint, *input_shape(actor.obs_dim, history))
    batch = torch.export.Dim("batch", min=1, max=1 << 20)
    with torch.no_grad(), warnings.catch_warnings():
        # nn.LSTM (agent.encoder: lstm) rebuilds its flat weight list while it is traced; the
        # exported program holds the weights all the same (tests/test_hardcore_features.py)
        warnings.filterwarnings("ignore", "The tensor attributes .*_flat_weights")
        program = torch.export.export(module, (example,), dynamic_shapes=({0: batch},))
    meta = {
        "input_shape": ["B", *input_shape(actor.obs_dim, history)],
        "output_shape": ["B", actor.act_dim],
        "history": history,
        "action_repeat": action_repeat,
    }
    with atomic_path(out) as tmp:
        torch.export.save(program, str(tmp), extra_files={META_FILE: json.dumps(meta)})
