"""Per-job result files in an output folder, so an interrupted run resumes from what already finished.

A job is identified by a hash of its function, its parameters and the evpose
source code; its result is one JSON file written atomically the moment the job
finishes. On restart, a job whose file exists with the same identity is not run
again; after a code change every job runs afresh (a stale result must not pass
for a new one). Failed jobs are never cached (a rerun retries them).
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

from evpose.io.atomic import atomic_path


@lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of every ``.py`` file of the installed evpose package (path and content), computed once per process."""
    import evpose

    root = Path(evpose.__file__).parent
    h = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        h.update(str(path.relative_to(root)).encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


@dataclass(frozen=True)
class Job:
    """One unit of work: a pure function of JSON-able parameters returning a JSON-able dict."""

    name: str
    """Human-readable label, unique within a run (e.g. ``velocity-fast/full/200hz``)."""
    fn: str
    """The function as ``"package.module:function"``, importable in any worker process."""
    params: dict = field(default_factory=dict)
    """Keyword arguments of ``fn``; must survive a JSON round trip unchanged."""

    def key(self) -> str:
        """Stable identity of the work (function + parameters + code), independent of where it runs."""
        blob = json.dumps({"fn": self.fn, "params": self.params, "code": code_version()}, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(blob.encode()).hexdigest()[:20]


class ResultCache:
    """Finished job results as ``<folder>/<job key>.json``."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)

    def path(self, job: Job) -> Path:
        return self.folder / f"{job.key()}.json"

    def get(self, job: Job) -> dict | None:
        """The stored result of ``job``, or None if it has not finished (or the file is unreadable)."""
        p = self.path(job)
        try:
            stored = json.loads(p.read_text())
        except (OSError, ValueError):
            return None
        # Guard against a hash collision or a hand-edited file: the identity must match exactly.
        if stored.get("fn") != job.fn or stored.get("params") != job.params or stored.get("code") != code_version():
            return None
        return stored.get("result")

    def put(self, job: Job, result: dict) -> None:
        self.folder.mkdir(parents=True, exist_ok=True)
        with atomic_path(self.path(job)) as tmp:
            tmp.write_text(json.dumps({"name": job.name, "fn": job.fn, "params": job.params, "code": code_version(), "result": result}, sort_keys=True) + "\n")
