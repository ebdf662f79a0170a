"""What a restart file's missing Adam moments cost: the updates after a restart with the run's own
moments, with a fresh Adam, and with moments estimated again from a refilled buffer
(bipedal_cli/adam_moments.py), all from one training state.

    python benchmarks/restart_moments.py runs/hardcore/RUN/state.pt --updates 200

The state gives the networks, the moments and the replay buffer. Its last ``--recent``
transitions (train.refill_steps by default: what a restart's refill holds, though played by
the policy of their own steps) stand in for the refilled buffer the estimate draws from. Then
three starts make the same updates (the same batches, the same noise) from the state's weights
for up to max(``--marks``) updates; a fourth, the run's own moments with other batches and
noise, shows how far batch draws alone take two paths apart. Printed per network (actor,
critics) at each mark: how far its weights are from the run's own (||W - W_own||), over how
far the run's own have moved (||W_own - W_0||). 0 is the run's own path; a fresh Adam's first
steps move every weight by about lr, where the run's own moments move most by far less. Also
the estimate's wall time.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import numpy as np  # noqa: E402
import torch  # noqa: E402
from record import run_recorded  # noqa: E402

from bipedal_cli.adam_moments import estimate_moments, without_moments  # noqa: E402
from bipedal_cli.buffer import ReplayBuffer  # noqa: E402
from bipedal_cli.checkpoint import load_checkpoint  # noqa: E402
from bipedal_cli.config import config_from_dict  # noqa: E402
from bipedal_cli.schedule import actor_lowest_atoms, batch_size_at  # noqa: E402
from bipedal_cli.train import Trainer  # noqa: E402

STARTS = (
    "the run's own moments",
    "the run's own moments, other batches",  # the noise floor: batch draws alone
    "a fresh Adam (no moments)",
    "moments estimated again",
)


def recent_buffer(buffer: ReplayBuffer, count: int) -> ReplayBuffer:
    """The last ``count`` transitions of ``buffer`` (in the order they came) in a buffer of
    their own."""
    count = min(count, buffer.size)
    recent = ReplayBuffer(count, buffer.obs_dim, buffer.act_dim, buffer.discount is not None)
    idx = (buffer.pos - count + np.arange(count)) % buffer.size
    for name in buffer.fields:
        getattr(recent, name)[:] = getattr(buffer, name)[idx]
    recent.size, recent.pos = count, 0
    return recent


def flat_weights(agent) -> dict[str, torch.Tensor]:
    agent.sync()
    return {
        name: torch.cat([p.detach().reshape(-1) for p in net.parameters()]).double()
        for name, net in (("actor", agent.actor), ("critics", agent.critic))
    }


def updates_from(trainer, state: dict, start: str, args) -> tuple[dict, float | None]:
    """The weights after each of ``args.marks`` updates from ``state`` with the moments of
    ``start``; and the estimate's seconds (None when there is none)."""
    agent, full = trainer.agent, trainer.buffer
    moments = state["agent"] if start in STARTS[:2] else without_moments(state["agent"])
    agent.load_state_dict(moments)
    batch_size = batch_size_at(trainer.step, trainer.cfg.agent)
    seconds = None
    if start == STARTS[3]:
        trainer.buffer = recent_buffer(full, args.recent)
        trainer.rng = np.random.default_rng(args.seed + 1)
        began = time.perf_counter()
        estimate_moments(trainer, batch_size)
        seconds = time.perf_counter() - began
        trainer.buffer = full
    seed = args.seed + (1000 if start == STARTS[1] else 0)
    agent.noise.manual_seed(seed)  # the same noise and batches for every start but the floor's
    rng = np.random.default_rng(seed)
    kept = {0: flat_weights(agent)}
    for n in range(1, max(args.marks) + 1):
        agent.update(agent.batch_to_tensors(full.sample(batch_size, rng)))
        if n in args.marks:
            kept[n] = flat_weights(agent)
    return kept, seconds


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("state", type=Path, help="a run's state.pt (with replay buffer)")
    parser.add_argument("--recent", type=int, default=None, help="default: train.refill_steps")
    parser.add_argument("--marks", type=int, nargs="+", default=[1, 10, 100, 200])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    state = load_checkpoint(args.state, "STATE")
    cfg = config_from_dict(state["config"], f"{args.state}: config")
    args.recent = args.recent or cfg.train.refill_steps
    with tempfile.TemporaryDirectory() as tmp:
        trainer = Trainer(cfg, Path(tmp) / "run")
        trainer.load_state_dict(state)
        agent = trainer.agent
        agent.actor_lowest_atoms = actor_lowest_atoms(trainer.step, cfg.agent)
        paths, seconds = {}, None
        for start in STARTS:
            paths[start], took = updates_from(trainer, state, start, args)
            seconds = took if took is not None else seconds
    print(
        f"{args.state}: step {trainer.step:,}, replay {trainer.buffer.size:,}, estimate from "
        f"the last {args.recent:,} in {seconds:.1f} s ({args.threads} thread(s))"
    )
    own = paths[STARTS[0]]
    print("| start | network | " + " | ".join(f"after {n:,}" for n in args.marks) + " |")
    print("|---|---|" + "---|" * len(args.marks))
    for start in STARTS[1:]:
        for net in ("actor", "critics"):
            cells = []
            for n in args.marks:
                moved = float(torch.linalg.vector_norm(own[n][net] - own[0][net]))
                apart = float(torch.linalg.vector_norm(paths[start][n][net] - own[n][net]))
                cells.append(f"{apart / moved:.2f}")
            print(f"| {start} | {net} | " + " | ".join(cells) + " |")


if __name__ == "__main__":
    run_recorded("restart_moments", main)
