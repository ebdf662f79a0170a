"""Where a sweep's study lives, and the one lock its workers share.

* no ``--storage`` (or a file path): Optuna's journal file, ``sweeps/<study>/journal.log``; no
  server, workers on one machine;
* ``sqlite:///FILE``: Optuna's RDB storage in one file, with heartbeats (one machine);
* ``postgresql+psycopg://USER@HOST/DB``: Optuna's RDB storage on a PostgreSQL server that every
  machine points at, with heartbeats: a worker that dies stops beating, the next worker to look
  marks its trial failed, and Optuna's retry callback queues the same parameters again.

The *gate* is a lock held while a worker counts the study's trials and asks for a new one, so
that the study-wide budget (``--trials``) is exact however many workers start at once: an
``fcntl.flock`` on a file beside the journal or SQLite file, or a PostgreSQL advisory lock.
"""

from __future__ import annotations

import os
import time
import zlib
from pathlib import Path

from .errors import UserError

JOURNAL_FILE = "journal.log"


def is_url(storage: str | None) -> bool:
    return storage is not None and "://" in storage


def redact(url: str) -> str:
    """The URL without its password, for messages."""
    if "@" not in url or "://" not in url:
        return url
    scheme, rest = url.split("://", 1)
    creds, host = rest.rsplit("@", 1)
    user = creds.split(":", 1)[0]
    return f"{scheme}://{user}:***@{host}" if ":" in creds else url


def open_storage(storage: str | None, study_dir: Path, heartbeat: int):
    """The Optuna storage for ``--storage`` (see the module docstring)."""
    import optuna

    if not is_url(storage):
        path = Path(storage) if storage else study_dir / JOURNAL_FILE
        path.parent.mkdir(parents=True, exist_ok=True)
        backend = optuna.storages.journal.JournalFileBackend(str(path))
        return optuna.storages.JournalStorage(backend)
    if not storage.startswith(("sqlite:///", "postgresql")):
        raise UserError(
            f"--storage {redact(storage)}: expected a journal file path, sqlite:///FILE or "
            "postgresql+psycopg://USER@HOST/DB"
        )
    return _rdb_storage(storage, heartbeat)


def _rdb_storage(url: str, heartbeat: int):
    """RDBStorage with heartbeats and retries; workers that start together may race to create
    its tables, so a failed first connection is retried a few times before it is an error."""
    import optuna
    import sqlalchemy.exc

    last: Exception | None = None
    for attempt in range(6):
        try:
            return optuna.storages.RDBStorage(
                url,
                engine_kwargs={"pool_pre_ping": True},
                heartbeat_interval=heartbeat,
                grace_period=2 * heartbeat,
                heartbeat_stale_trial_callback=optuna.storages.RetryHeartbeatStaleTrialCallback(
                    max_retry=3
                ),
            )
        except sqlalchemy.exc.OperationalError as exc:  # unreachable: no point in waiting long
            last = exc
            if attempt >= 1:
                break
        except (sqlalchemy.exc.SQLAlchemyError, ImportError) as exc:
            last = exc
        time.sleep(0.5 * (attempt + 1))
    reason = str(getattr(last, "orig", None) or last).strip().splitlines()[0][:160]
    raise UserError(f"--storage {redact(url)}: cannot open the study database ({reason})")


class FileGate:
    """An exclusive ``flock`` on a file: the workers of one machine."""

    def __init__(self, path: Path) -> None:
        self.path, self.fd = path, None

    def acquire(self) -> None:
        import fcntl

        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW, 0o644)
        fcntl.flock(self.fd, fcntl.LOCK_EX)

    def release(self) -> None:
        import fcntl

        if self.fd is not None:
            fcntl.flock(self.fd, fcntl.LOCK_UN)
            os.close(self.fd)
            self.fd = None


class PostgresGate:
    """A PostgreSQL advisory lock keyed by the study's name: the workers of every machine."""

    def __init__(self, url: str, study: str) -> None:
        import sqlalchemy

        self.engine = sqlalchemy.create_engine(url, poolclass=sqlalchemy.pool.NullPool)
        self.key = zlib.crc32(f"bipedal-sweep:{study}".encode())
        self.conn = None

    def acquire(self) -> None:
        import sqlalchemy

        self.conn = self.engine.connect()
        self.conn.execute(sqlalchemy.text("SELECT pg_advisory_lock(:k)"), {"k": self.key})

    def release(self) -> None:
        import sqlalchemy

        if self.conn is not None:
            self.conn.execute(sqlalchemy.text("SELECT pg_advisory_unlock(:k)"), {"k": self.key})
            self.conn.close()
            self.conn = None


def make_gate(storage: str | None, study: str, study_dir: Path):
    if storage is None or not is_url(storage):
        journal = Path(storage) if storage else study_dir / JOURNAL_FILE
        return FileGate(journal.with_name(journal.name + ".gate"))  # .lock is Optuna's own
    if storage.startswith("sqlite:///"):
        return FileGate(Path(storage[len("sqlite:///") :] + ".gate"))
    return PostgresGate(storage, study)
