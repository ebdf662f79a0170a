"""Choosing a run's policy on seeds that did not pick it.

A run's periodic evaluations (20 episodes on seeds from ``train.eval_seed``) rank its kept
policies (``train.keep_policies``), its ``best_policy.pt`` and its ``policy.pt``. The best of
many noisy 20-episode means is biased upward (the winner's curse), and choosing among them with
``bipedal eval``'s seeds 0-99 would bias the reported score the same way. So the top few are
evaluated again on held-out seeds (2,000,000 on by default) and the best there is the choice;
its ``bipedal eval`` on seeds 0-99 is then a clean estimate.

The best of many on 100 held-out episodes is itself the best of many noisy means: with K
candidates whose true scores are close, the round's winner leads by luck about as often as by
merit. ``--confirm N`` adds a second round on the next N seeds between two finalists only (the
round's winner and the incumbent, the first policy file named, or else the runner-up); two
candidates leave almost no room for the winner's curse.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from .checkpoint import BEST_POLICY_FILE, POLICIES_DIR, POLICY_FILE, load_checkpoint
from .errors import UserError

HELD_OUT_SEED = 2_000_000  # apart from eval's 0-99 and the periodic evaluations' 1,000,000 on


@dataclass
class Candidate:
    path: Path
    run: str
    step: int  # policy steps
    env: str
    periodic: float | None  # the periodic evaluation's mean at this very step, if there was one
    periodic_falls: int | None
    sha256: str = ""  # of the file's bytes, set by ``distinct``: the policy's identity in reports


def describe(path: Path) -> Candidate:
    """A policy file as a candidate, with the periodic evaluation it records for its own step."""
    meta = load_checkpoint(path, "RUN_DIR")["meta"]
    step = int(meta["steps"])
    last = meta.get("last_eval") or {}
    at_step = last.get("step") == step
    in_run = path.name in (BEST_POLICY_FILE, POLICY_FILE) or path.parent.name == POLICIES_DIR
    run = path.parent.parent if path.parent.name == POLICIES_DIR else path.parent
    return Candidate(
        path,
        run.name if in_run else path.name,
        step,
        meta["env"],
        float(last["mean"]) if at_step else None,
        int(last["falls"]) if at_step else None,
    )


def run_candidates(run_dir: Path) -> list[Candidate]:
    """The kept policies, ``best_policy.pt`` and ``policy.pt`` of a run, one per step; a policy
    file given instead of a run (a shipped policy to compare against) is one candidate."""
    if run_dir.is_file():
        return [describe(run_dir)]
    if not run_dir.is_dir():
        raise UserError(f"RUN_DIR {run_dir}: not a run directory or a policy file")
    paths = sorted((run_dir / POLICIES_DIR).glob("step-*.pt"))
    paths += [p for p in (run_dir / BEST_POLICY_FILE, run_dir / POLICY_FILE) if p.is_file()]
    if not paths:
        raise UserError(f"RUN_DIR {run_dir}: holds no policy ({POLICY_FILE}, {POLICIES_DIR}/)")
    by_step: dict[int, Candidate] = {}
    for path in paths:
        found = describe(path)
        by_step.setdefault(found.step, found)
    return list(by_step.values())


def distinct(candidates: list[Candidate]) -> list[Candidate]:
    """One candidate per policy file content: a branch's copy of its source's best policy, or
    a ``best_policy.pt`` equal to a kept one, is evaluated once (the first named wins)."""
    seen: set[str] = set()
    out = []
    for c in candidates:
        c.sha256 = digest = hashlib.sha256(c.path.read_bytes()).hexdigest()
        if digest not in seen:
            seen.add(digest)
            out.append(c)
    return out


def top_candidates(candidates: list[Candidate], k: int) -> list[Candidate]:
    """The ``k`` best by periodic evaluation (later steps first among ties); candidates with
    none come after all that have one, latest first."""

    def key(c: Candidate) -> tuple[bool, float, int]:
        return (c.periodic is not None, c.periodic or 0.0, c.step)

    return sorted(candidates, key=key, reverse=True)[:k]


def finalists(means: list[float], named: int) -> list[int]:
    """The confirmation round's candidates, as indices into the first round's: its winner and
    the incumbent (index 0, when policy files were named), or else the runner-up. One index
    when the winner is the incumbent or there is no other candidate."""
    ranked = sorted(range(len(means)), key=lambda i: means[i], reverse=True)
    other = 0 if named else (ranked[1] if len(ranked) > 1 else ranked[0])
    return [ranked[0]] if other == ranked[0] else [ranked[0], other]
