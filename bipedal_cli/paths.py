"""Validating output paths before any work starts, so bad input fails fast and writes nothing."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from .errors import UserError


def printable(name: str | Path) -> str:
    """A path as text that can be printed or drawn: bytes that are not UTF-8 become U+FFFD."""
    return os.fsencode(str(name)).decode("utf-8", "replace")


def check_output_path(
    path: Path, option: str, suffixes: tuple[str, ...] | None = None, force: bool = True
) -> None:
    """Raise a one-line :class:`UserError` unless ``path`` can be written as asked.

    ``suffixes``: accepted extensions (None: any). ``force=False`` refuses an existing file.
    """
    suffix = path.suffix.lower()
    if suffixes is not None and suffix not in suffixes:
        raise UserError(
            f"{option} {path}: unknown extension {suffix or '(none)'!r}; "
            f"expected {' or '.join(suffixes)}"
        )
    parent = path.parent
    if path.is_dir():
        raise UserError(f"{option} {path}: is a directory; expected a file path")
    if not parent.is_dir():
        raise UserError(f"{option} {path}: directory {parent} does not exist")
    if not _can_create_in(parent):
        raise UserError(f"{option} {path}: directory {parent} is not writable")
    if path.exists() and not force:
        raise UserError(f"{option} {path}: already exists; pass --force to overwrite it")


def _can_create_in(directory: Path) -> bool:
    """Whether a file can be created in ``directory``, found by creating (and removing) one.

    ``os.access`` answers from the permission bits, which root passes even where the file system
    refuses files (``/proc``, a read-only mount), so the output would fail only after the work.
    """
    try:
        with tempfile.TemporaryFile(dir=directory):
            return True
    except OSError:
        return False


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix); rename it over ``path`` on success.

    A crash or kill at any moment leaves the old ``path`` as it was, and the temporary file is
    removed when the body raises.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{path.stem}.", suffix=f".tmp{path.suffix}", dir=path.parent
    )
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o644)  # mkstemp makes it owner-only; the result is a normal file
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)
