"""The dataset manifest: one SQLite file (``DS/manifest.sqlite``), the build's memory.

Stdlib ``sqlite3`` in WAL mode; every state change is one transaction, so a build killed
at any moment (``kill -9`` included) leaves the manifest as it was after the last pair it
recorded. A pair is recorded ``done`` only after its folder has been renamed into place
(:func:`map2map.datasets.pair.write_pair`), so a ``done`` row always has a complete
folder; a folder without a ``done`` row is left-over work and is removed on resume.

Tables
------
``info(key, value)``
    The build's identity (JSON): parameters, seed, plan source and its digest, the
    format version; the cleaner's report; the split fractions.
``pairs(idx, status, plan_id, kind, split, attempts, reason, coverage, wall_error,
ate, path_length, stop_reason, wall_seconds, worker, meta, p_complete, label, clean,
finished)``
    One row per pair that finished (``done`` or ``failed``) or whose worker died
    (``crashed``, with its attempt count).

Examples
--------
>>> import tempfile, pathlib
>>> m = Manifest(pathlib.Path(tempfile.mkdtemp()) / "manifest.sqlite")
>>> m.set_info("params", {"seed": 0})
>>> m.record_failed(3, "plan 3", "simulate", "plan has no free space", split="train")
>>> m.get_info("params"), m.counts()
({'seed': 0}, {'failed': 1})
>>> m.close()
"""

from __future__ import annotations

import json
import os
import sqlite3
import time
from pathlib import Path
from typing import Any

from ..core.errors import InputError

__all__ = ["Manifest", "SCHEMA_VERSION"]

SCHEMA_VERSION = 1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS info (key TEXT PRIMARY KEY, value TEXT NOT NULL);
CREATE TABLE IF NOT EXISTS pairs (
    idx INTEGER PRIMARY KEY,
    status TEXT NOT NULL,
    plan_id TEXT,
    kind TEXT,
    split TEXT,
    attempts INTEGER NOT NULL DEFAULT 0,
    reason TEXT,
    coverage REAL,
    wall_error REAL,
    ate REAL,
    path_length REAL,
    stop_reason TEXT,
    wall_seconds REAL,
    worker TEXT,
    meta TEXT,
    p_complete REAL,
    label TEXT,
    clean TEXT,
    finished TEXT
);
CREATE INDEX IF NOT EXISTS pairs_status ON pairs(status);
"""


class Manifest:
    """A dataset's SQLite manifest (see the module docstring).

    Parameters
    ----------
    path : path-like
        The database file; created with its tables when absent.
    """

    def __init__(self, path: str | os.PathLike):
        self.path = Path(path)
        try:
            self.db = sqlite3.connect(self.path, timeout=30.0, isolation_level=None)
            self.db.execute("PRAGMA journal_mode=WAL")
            self.db.execute("PRAGMA synchronous=NORMAL")
            self.db.executescript(_SCHEMA)
        except sqlite3.DatabaseError as exc:
            raise InputError(self.path, f"not a readable dataset manifest ({exc})") from None
        self.db.row_factory = sqlite3.Row

    def close(self) -> None:
        self.db.close()

    def __enter__(self) -> Manifest:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    # ------------------------------------------------------------------ info
    def get_info(self, key: str, default: Any = None) -> Any:
        row = self.db.execute("SELECT value FROM info WHERE key = ?", (key,)).fetchone()
        return default if row is None else json.loads(row[0])

    def set_info(self, key: str, value: Any) -> None:
        with self.db:
            self.db.execute(
                "INSERT INTO info(key, value) VALUES (?, ?) "
                "ON CONFLICT(key) DO UPDATE SET value = excluded.value",
                (key, json.dumps(value, sort_keys=True)),
            )

    # ----------------------------------------------------------------- pairs
    def finished(self) -> set[int]:
        """Indices recorded ``done`` or ``failed`` (nothing left to do for them)."""
        rows = self.db.execute("SELECT idx FROM pairs WHERE status IN ('done', 'failed')")
        return {r[0] for r in rows}

    def attempts(self) -> dict[int, int]:
        """Worker deaths so far per pair index (rows with status ``crashed``)."""
        rows = self.db.execute("SELECT idx, attempts FROM pairs WHERE status = 'crashed'")
        return {r[0]: r[1] for r in rows}

    def counts(self) -> dict[str, int]:
        rows = self.db.execute("SELECT status, COUNT(*) FROM pairs GROUP BY status")
        return {r[0]: r[1] for r in rows}

    def record_done(self, idx: int, plan_id: str, kind: str, meta: dict, *, split: str,
                    wall_seconds: float, worker: str = "") -> None:  # fmt: skip
        """Record a pair whose folder is in place (one transaction)."""
        with self.db:
            self.db.execute(
                "INSERT OR REPLACE INTO pairs(idx, status, plan_id, kind, split, attempts, "
                "reason, coverage, wall_error, ate, path_length, stop_reason, wall_seconds, "
                "worker, meta, finished) VALUES (?, 'done', ?, ?, ?, "
                "COALESCE((SELECT attempts FROM pairs WHERE idx = ?), 0), NULL, "
                "?, ?, ?, ?, ?, ?, ?, ?, ?)",
                (int(idx), plan_id, kind, split, int(idx), meta.get("coverage"),
                 meta.get("wall_error_m"), meta.get("ate_rmse_m"), meta.get("path_length_m"),
                 meta.get("stop_reason"), float(wall_seconds), worker,
                 json.dumps(meta, sort_keys=True), _now()),
            )  # fmt: skip

    def record_failed(self, idx: int, plan_id: str, kind: str, reason: str, *, split: str,
                      wall_seconds: float = 0.0, worker: str = "") -> None:  # fmt: skip
        """Record a pair that cannot be made (bad plan, or its worker died too often)."""
        with self.db:
            self.db.execute(
                "INSERT OR REPLACE INTO pairs(idx, status, plan_id, kind, split, attempts, "
                "reason, wall_seconds, worker, finished) VALUES (?, 'failed', ?, ?, ?, "
                "COALESCE((SELECT attempts FROM pairs WHERE idx = ?), 0), ?, ?, ?, ?)",
                (int(idx), plan_id, kind, split, int(idx), reason, float(wall_seconds),
                 worker, _now()),
            )  # fmt: skip

    def record_crash(self, idx: int, plan_id: str, kind: str, reason: str, *,
                     split: str) -> int:  # fmt: skip
        """Count one worker death on pair ``idx``; returns its attempts so far."""
        with self.db:
            self.db.execute(
                "INSERT INTO pairs(idx, status, plan_id, kind, split, attempts, reason) "
                "VALUES (?, 'crashed', ?, ?, ?, 1, ?) ON CONFLICT(idx) DO UPDATE SET "
                "attempts = attempts + 1, reason = excluded.reason",
                (int(idx), plan_id, kind, split, reason),
            )
        return int(self.db.execute("SELECT attempts FROM pairs WHERE idx = ?",
                                   (int(idx),)).fetchone()[0])  # fmt: skip

    def rows(self, status: str | None = None, limit: int | None = None) -> list[sqlite3.Row]:
        """Pair rows in index order (optionally of one status)."""
        q = "SELECT * FROM pairs"
        args: tuple = ()
        if status:
            q += " WHERE status = ?"
            args = (status,)
        q += " ORDER BY idx"
        if limit:
            q += f" LIMIT {int(limit)}"
        return list(self.db.execute(q, args))

    def set_clean(self, values: list[tuple[int, float, str | None, str]]) -> None:
        """Store the cleaner's ``(idx, p_complete, label, clean)`` (one transaction)."""
        with self.db:
            self.db.executemany(
                "UPDATE pairs SET p_complete = ?, label = ?, clean = ? WHERE idx = ?",
                [(float(p), lab, c, int(i)) for i, p, lab, c in values],
            )


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%S", time.gmtime())
