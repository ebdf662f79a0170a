"""Does torch.compile of the networks speed up a TQC update on this CPU? (one thread)

    python benchmarks/compile_vs_eager.py

Compiles the D2RL forward of the actor, critics and target critics with inductor (AOTAutograd
compiles their backward too) and times eager and compiled updates on the same batches,
interleaved so that machine noise hits both alike. The losses stay eager: the closed-form
quantile loss is already a handful of small ops.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
import torch

from bipedal_cli.agent import TQCAgent
from bipedal_cli.buffer import ReplayBuffer
from bipedal_cli.config import AgentConfig


def make_agent(compiled: bool) -> TQCAgent:
    torch.manual_seed(0)
    agent = TQCAgent(AgentConfig(), 24, 4)
    if compiled:
        for module in (agent.critic.net, agent.critic_target.net, agent.actor.net):
            module.forward = torch.compile(module.forward, dynamic=False)
    return agent


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--updates", type=int, default=160)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    buf = ReplayBuffer(10_000, 24, 4)
    rng = np.random.default_rng(0)
    for _ in range(5000):
        buf.add(
            rng.normal(size=24),
            rng.uniform(-1, 1, 4),
            rng.normal(),
            rng.normal(size=24),
            rng.random() < 0.01,
        )
    batches = [
        {k: torch.as_tensor(v) for k, v in buf.sample(64, rng).items()}
        for _ in range(args.updates + 5)
    ]
    agents = {"eager": make_agent(False), "compiled": make_agent(True)}
    start = time.perf_counter()
    for b in batches[:5]:
        agents["compiled"].update(b)
    print(f"first compiled updates (compilation): {time.perf_counter() - start:.1f} s")
    for b in batches[:5]:
        agents["eager"].update(b)
    spent = dict.fromkeys(agents, 0.0)
    chunk = args.updates // 4
    for rep in range(4):
        for name, agent in agents.items():
            start = time.perf_counter()
            for b in batches[5 + rep * chunk : 5 + (rep + 1) * chunk]:
                agent.update(b)
            spent[name] += time.perf_counter() - start
    print(f"torch {torch.__version__}, {args.threads} thread(s), batch 64, paper sizes")
    for name, seconds in spent.items():
        print(f"{name:>9}: {4 * chunk / seconds:.1f} updates/s")


if __name__ == "__main__":
    from record import run_recorded

    run_recorded("compile_vs_eager", main)
