"""Every file that README.md and docs/*.md name or show is in the repository: a figure's source
(metrics.csv, eval JSON, benchmark output) that is not committed is not a source. Paths are
checked against git's list of tracked and not-ignored files, as a fresh clone would have them. A
file that left the tree is named as git names it in a commit, ``<commit>:path`` (as in ``git show
<commit>:path > file``), and is checked in that commit."""

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
REPO_PATH = r"(?:docs|benchmarks|configs|checkpoints|bipedal_cli|tests)/[\w./-]*"
NAMED = re.compile(rf"(?<![\w/.:])({REPO_PATH})")  # not after "<commit>:"
AT_COMMIT = re.compile(rf"\b([0-9a-f]{{7,40}}):({REPO_PATH})")
LINKED = re.compile(r"\]\(([^)#\s]+)\)")


def repository_files() -> set[str]:
    out = subprocess.run(
        ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    if out.returncode != 0:
        pytest.skip("not a git checkout")
    files = set(out.stdout.split())
    folders = {str(parent) + "/" for f in files for parent in Path(f).parents if str(parent) != "."}
    return files | folders  # folders as "a/b/"


def named_paths(doc: Path) -> set[str]:
    text = doc.read_text()
    paths = {
        m.group(1).rstrip(".,:;")
        for m in NAMED.finditer(text)
        if text[m.end() : m.end() + 1] not in ("*", "{", "<", "[")  # a pattern, not a path
    }
    for target in LINKED.findall(text):
        if "://" not in target:
            paths.add(str((doc.parent / target).resolve().relative_to(ROOT)))
    return {p for p in paths if not re.search(r"[<>*{}]", p)}


def in_commit(commit: str, path: str) -> bool:
    out = subprocess.run(
        ["git", "cat-file", "-e", f"{commit}:{path}"], cwd=ROOT, capture_output=True
    )
    return out.returncode == 0


def paths_at_commits(doc: Path) -> set[tuple[str, str]]:
    """The ``<commit>:path`` names in a document: files that left the tree, kept in git."""
    return {(m.group(1), m.group(2).rstrip(".,:;")) for m in AT_COMMIT.finditer(doc.read_text())}


@pytest.mark.parametrize("doc", DOCS, ids=lambda d: d.name)
def test_every_path_a_document_names_is_committed(doc):
    files = repository_files()
    missing = sorted(
        p for p in named_paths(doc) if p not in files and p.rstrip("/") + "/" not in files
    )
    assert not missing, f"{doc.name} names files a fresh clone lacks: {missing}"
    lost = sorted(f"{c}:{p}" for c, p in paths_at_commits(doc) if not in_commit(c, p))
    assert not lost, f"{doc.name} names files those commits lack: {lost}"


def test_the_checker_sees_a_missing_path(tmp_path):
    doc = ROOT / "docs" / "hardcore.md"
    assert "checkpoints/bipedal_hardcore.eval.json" in named_paths(ROOT / "README.md")
    assert "docs/images/hardcore_runs.png" in named_paths(doc)  # ](images/...) from docs/
    assert "docs/runs/nope/metrics.csv" not in repository_files()
    # a file named at a commit is looked up in that commit, not in the tree
    named = tmp_path / "named.md"
    named.write_text(
        "`git show 409ad4c:checkpoints/gone.pt > a.pt`, checkpoints/bipedal_hardcore.pt"
    )
    assert named_paths(named) == {"checkpoints/bipedal_hardcore.pt"}
    assert paths_at_commits(named) == {("409ad4c", "checkpoints/gone.pt")}
    assert in_commit("409ad4c", "checkpoints/bipedal_hardcore.pt")
    assert not in_commit("409ad4c", "checkpoints/gone.pt")
