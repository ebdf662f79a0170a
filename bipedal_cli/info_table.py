"""``bipedal info``: what a checkpoint holds, as a table."""

from __future__ import annotations

from typing import Any

from rich.table import Table


def _brief(value: Any) -> str:
    """An evaluation or curriculum dict as its few telling fields."""
    if value is None:
        return "-"
    if not isinstance(value, dict):
        return str(value)
    keep = ("mean", "std", "episodes", "falls", "step", "stage")
    parts = [
        f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
        for k, v in value.items()
        if k in keep
    ]
    return ", ".join(parts) or str(value)


def checkpoint_table(data: dict, title: str) -> Table:
    """``bipedal info``: what a checkpoint (already checked by checkpoint.py) holds."""
    from .checkpoint import TRAIN_FORMAT
    from .checkpoint_contents import training_progress
    from .config import config_from_dict

    cfg = config_from_dict(data["config"])
    if data["format"] == TRAIN_FORMAT:
        meta = {
            **training_progress(data),
            "replay buffer": f"{int(data['buffer']['size']):,} transitions",
            "adam moments": _adam_moments(data),
            "curriculum": data.get("curriculum"),
        }
    else:
        meta = {k: v for k, v in data["meta"].items() if k not in ("env", "seed")}
    table = Table(title=title, show_header=False)
    table.add_column(style="cyan")
    table.add_column()
    kind = (
        "policy"
        if data["format"] != TRAIN_FORMAT
        else "restart file"
        if data.get("restart")
        else "training state"
    )
    table.add_row("kind", f"{kind} ({data['format']} v{data['version']})")
    table.add_row("env", data["env"])
    table.add_row("obs / action size", f"{data['obs_dim']} / {data['act_dim']}")
    a = cfg.agent
    table.add_row(
        "policy",
        f"last {a.history} observation(s)"
        + (f" read by an LSTM of width {a.encoder_hidden}" if a.encoder == "lstm" else "")
        + f"; each action held for {a.action_repeat} env step(s)",
    )
    for key, value in meta.items():
        table.add_row(key.replace("_", " "), _brief(value))
    table.add_row("seed", str(cfg.seed))
    for section in ("agent", "train"):
        items = getattr(cfg, section).__dict__.items()
        table.add_row(section, ", ".join(f"{k}={v}" for k, v in items))
    return table


def _adam_moments(data: dict) -> str:
    """Whether a training state holds the actor's and critics' Adam moments
    (:mod:`bipedal_cli.adam_moments`)."""
    if data["agent"]["critic_opt"]["state"]:
        return "kept"
    if data.get("restart"):
        return "left out (estimated again after the refill)"
    return "none yet (no update made)"
