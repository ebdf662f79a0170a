"""Every experiment against the bar: the held-out falls per 100 episodes and mean return of each
run's kept policies, by window of policy steps, minus the shipped policy's on the same seeds,
from `bipedal select --json` reports (each plays its own seed block, so only differences
within a block are compared). Prints the table and draws it.

    python benchmarks/heldout_falls.py docs/runs/hardcore-select-session13.json \\
        docs/runs/hardcore-select-session20.json --every 100000 \\
        --out docs/images/hardcore_heldout_falls.png

Run from the project root. A policy file named on its own in a report (a run's last policy, or
a branch point) is its own point; a report that did not play the policy now in
`checkpoints/bipedal_hardcore.pt` (same sha256) is an error, not a point at zero.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
from dataclasses import dataclass
from pathlib import Path

from select_by_run import summarise

REFERENCE = "checkpoints/bipedal_hardcore.pt"
HEADER = (
    "| report | run | from step | policies | falls per 100 | minus shipped "
    "| return minus shipped |\n"
    "|---|---|---|---|---|---|---|"
)


@dataclass(frozen=True)
class Window:
    run: str  # a run directory, or a policy file named on its own
    first_step: int
    policies: int
    falls: float  # per 100 held-out episodes, mean over the window's policies
    extra_falls: float  # falls minus the reference's on the same seeds
    extra_return: float  # mean held-out return minus the reference's

    @property
    def single_file(self) -> bool:
        return self.run.endswith(".pt")


def against_reference(report: dict, every: int, sha256: str, reference: str = REFERENCE):
    """The windows of every run in one report but the reference (that path with that sha256:
    the file at the path changed whenever a new policy shipped), each against the reference."""
    matches = [c for c in report["candidates"] if c["path"] == reference]
    if len(matches) != 1 or matches[0].get("sha256") != sha256:
        raise ValueError(f"the report does not play {reference} with sha256 {sha256[:12]}...")
    rows = summarise(report["candidates"], every)
    (bar,) = [row for row in rows if row.run == reference]
    return [
        Window(
            row.run,
            row.first_step,
            row.policies,
            row.falls_per_100,
            row.falls_per_100 - bar.falls_per_100,
            row.mean_return - bar.mean_return,
        )
        for row in rows
        if row.run != reference
    ]


def row_label(report: Path, run: str) -> str:
    """'session13: lrdecay-cvar25-seed1' for a run directory or its policy.pt."""
    path = Path(run)
    name = path.parent.name if path.name == "policy.pt" else path.name.removesuffix(".pt")
    return f"{report.stem.split('-')[-1]}: {name}"


def draw(rows: dict[str, list[Window]], every: int, out: Path) -> None:
    """One row per run and report, top to bottom in the reports' order; a dot per window of
    kept policies, a ring for a policy file named on its own."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = list(rows)
    fig, axes = plt.subplots(1, 2, sharey=True, figsize=(11, 0.3 * len(labels) + 1.6))
    panels = (
        ("extra_falls", "falls per 100 minus the shipped policy's"),
        ("extra_return", "mean return minus the shipped policy's"),
    )
    for ax, (field, title) in zip(axes, panels, strict=True):
        for row, label in enumerate(labels):
            y = len(labels) - 1 - row
            for w in rows[label]:
                face = "none" if w.single_file else "C0"
                ax.plot(getattr(w, field), y, "o", mfc=face, mec="C0", ms=6)
        ax.axvline(0.0, color="black", linewidth=1)
        ax.set_xlabel(title, fontsize=9)
        ax.grid(axis="x", alpha=0.3)
    axes[0].set_yticks(range(len(labels)), labels[::-1], fontsize=8)
    fig.suptitle(
        f"Held-out seeds: each run's kept policies by {every:,}-step window (dots), "
        "a policy file on its own (ring)",
        fontsize=10,
    )
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("reports", type=Path, nargs="+", help="`bipedal select --json` files")
    parser.add_argument("--every", type=int, default=100_000, help="window of policy steps")
    parser.add_argument("--out", type=Path, help="write the figure here (.png)")
    args = parser.parse_args()
    sha256 = hashlib.sha256(Path(REFERENCE).read_bytes()).hexdigest()
    print(HEADER)
    rows: dict[str, list[Window]] = {}
    for report in args.reports:
        try:
            windows = against_reference(json.loads(report.read_text()), args.every, sha256)
        except ValueError as err:
            raise SystemExit(f"{report}: {err}") from None
        for w in windows:
            print(
                f"| {report.name} | {w.run} | {w.first_step:,} | {w.policies} | {w.falls:.1f} "
                f"| {w.extra_falls:+.1f} | {w.extra_return:+.1f} |"
            )
            rows.setdefault(row_label(report, w.run), []).append(w)
    if args.out:
        draw(rows, args.every, args.out)
        print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
