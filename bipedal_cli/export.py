"""A standalone policy file: ``torch.export`` of the deterministic actor, usable with torch alone.

    policy = torch.export.load("policy.pt2").module()
    actions = policy(obs)          # obs: (B, 24) float32 -> actions: (B, 4) in [-1, 1]

TorchScript is deprecated in current torch; ``torch.export`` is its replacement. The exported
program holds the weights and the graph, not our Python code, so loading needs nothing of this
package.
"""

from __future__ import annotations

from pathlib import Path

import torch

from .paths import atomic_path

EXPORT_SUFFIXES = (".pt2", ".pt")


def export_policy(actor: torch.nn.Module, out: Path, batch_hint: int = 8) -> None:
    """Export ``actor.deterministic`` with a dynamic batch dimension and save it to ``out``."""
    actor = actor.cpu().eval()
    example = torch.zeros(batch_hint, actor.obs_dim)
    batch = torch.export.Dim("batch", min=1, max=1 << 20)
    with torch.no_grad():
        program = torch.export.export(actor, (example,), dynamic_shapes=({0: batch},))
    with atomic_path(out) as tmp:
        torch.export.save(program, str(tmp))
