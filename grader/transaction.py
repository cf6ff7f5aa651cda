"""A change to a graded class made whole or not at all (issue 30): :class:`Transaction`, and the
lock every command that changes a class holds while it reads, checks and commits
(:func:`class_lock`).

A command stages every file it will write (records, feedback pages, the gradebook, the key,
the overrides) and the lines it will add to the audit trail, and commits them together: each
file is written beside its target as a hidden temporary, then one small *journal* file
(``OUT/.journal``) names every rename and the trail's lines. Writing the journal is the commit
point. The renames and the trail's lines follow; the journal is removed last. A process killed
before the journal exists leaves only temporaries, which the next command removes: the class as
before. Killed after, the next command that takes the lock finds the journal and finishes it
(:func:`recover`): the class as after, with the trail's lines appended once (each carries the
transaction's id, so a line that reached the trail is not written again). grader/API.md says
why a journal and not a database.

Floor 4 of grader/ (the unit, what it is graded against, where its records go; grader/API.md).
"""

from __future__ import annotations

import json
import os
import tempfile
import uuid
from collections.abc import Iterable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from grader.audit import append_lines, trail_has, trail_line
from grader.graded_folder import FEEDBACK, RESULTS, run_lock
from grader.results import TEMP_SUFFIX, remove_stale_temporaries

JOURNAL = ".journal"
"""The committed transaction's journal, in the output folder, while it is being applied."""


def _fsync_folder(folder: Path) -> None:
    fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _holds(path: Path, data: bytes) -> bool:
    """Whether ``path`` is a file holding exactly ``data``."""
    try:
        if path.stat().st_size != len(data):
            return False
        return path.read_bytes() == data
    except OSError:
        return False


def _staged(path: Path, data: bytes, durable: bool) -> Path:
    """``data`` in a hidden temporary beside ``path`` (mode 0600), flushed to disk if
    ``durable``; its path."""
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=TEMP_SUFFIX, dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            if durable:
                f.flush()
                os.fsync(f.fileno())
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return Path(tmp)


class Transaction:
    """Files and trail lines of one change to the class in ``out``, committed together.

    ``durable`` files (records, the key, the overrides: what cannot be derived) reach the disk
    before the commit point; the views (pages, tables, the report) are written the same way but
    not flushed one by one, since every command rebuilds them."""

    def __init__(self, out: Path) -> None:
        self.out = Path(out)
        self.id = uuid.uuid4().hex
        self._files: dict[Path, tuple[bytes, bool]] = {}
        self._removed: list[Path] = []
        self._lines: list[dict] = []

    def write(self, path: Path, text: str | bytes, *, durable: bool = True) -> None:
        """Stage ``path`` to hold ``text`` (UTF-8; a lone surrogate as its escape) — unless it
        holds exactly that already, which leaves it untouched."""
        data = text if isinstance(text, bytes) else \
            text.encode("utf-8", errors="backslashreplace")
        if _holds(Path(path), data):
            self._files.pop(Path(path), None)
            return
        self._files[Path(path)] = (data, durable)

    def remove(self, path: Path) -> None:
        """Stage the removal of ``path`` (nothing if it is absent by then)."""
        self._removed.append(Path(path))

    def trail(self, event: str, changes: Iterable[Mapping[str, Any]] = (), why: str = "",
              **details: Any) -> dict:
        """Stage one line of the audit trail (:func:`grader.audit.trail_line`); the line."""
        line = trail_line(event, changes, why, transaction=self.id, **details)
        self._lines.append(line)
        return line

    @property
    def empty(self) -> bool:
        return not (self._files or self._removed or self._lines)

    def commit(self) -> None:
        """Write everything staged, whole (module docstring). Raises only before the commit
        point (nothing then changed but temporaries, which are removed)."""
        if self.empty:
            return
        staged: list[tuple[Path, Path]] = []
        try:
            for path, (data, durable) in self._files.items():
                staged.append((_staged(path, data, durable), path))
            journal = {"id": self.id, "renames": [[_rel(t, self.out), _rel(p, self.out)]
                                                  for t, p in staged],
                       "removes": [_rel(p, self.out) for p in self._removed],
                       "trail": self._lines}
            _write_journal(self.out, journal)
        except BaseException:
            for tmp, _ in staged:
                tmp.unlink(missing_ok=True)
            raise
        apply_journal(self.out)


def _rel(path: Path, out: Path) -> str:
    return os.path.relpath(path, out)


def _write_journal(out: Path, journal: dict) -> None:
    # ASCII: a file name that is not UTF-8 (a surrogate escape) round-trips as \\udcxx
    tmp = _staged(out / JOURNAL, json.dumps(journal).encode("ascii"),
                  durable=True)
    os.replace(tmp, out / JOURNAL)  # the commit point
    _fsync_folder(out)


def apply_journal(out: Path) -> bool:
    """Finish the transaction whose journal is in ``out``, if there is one: every rename not yet
    done, every removal, the trail's lines unless they reached it; then the journal removed.
    Idempotent: a kill in here is finished by the next call. Whether there was one."""
    path = Path(out) / JOURNAL
    try:
        journal = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        return False
    folders = set()
    for tmp, target in journal["renames"]:
        tmp, target = Path(out) / tmp, Path(out) / target
        if tmp.exists():
            os.replace(tmp, target)
        folders.add(target.parent)
    for removed in journal["removes"]:
        (Path(out) / removed).unlink(missing_ok=True)
        folders.add((Path(out) / removed).parent)
    if journal["trail"] and not trail_has(out, journal["id"]):
        append_lines(out, journal["trail"])
    for folder in folders:
        _fsync_folder(folder)
    path.unlink()
    return True


def recover(out: Path, hw: Path | None = None) -> bool:
    """What a killed command left in ``out`` made whole: a committed journal finished
    (:func:`apply_journal`), then every temporary of an uncommitted one removed (in ``out``,
    its records and pages, and ``hw`` for the key). Whether a journal was finished."""
    finished = apply_journal(out)
    remove_stale_temporaries(*filter(None, (out, out / RESULTS, out / FEEDBACK, hw)))
    return finished


LOCK_WAIT = 600.0
"""Seconds a command waits for another one holding the class (``--wait``)."""


@contextmanager
def class_lock(out: Path, hw: Path | None = None, *, command: str,
               wait: float = LOCK_WAIT) -> Iterator[None]:
    """Hold ``out``'s lock (waiting up to ``wait`` seconds for a command holding it, saying so
    on stderr once), with whatever a killed command left made whole first (:func:`recover`)."""
    with run_lock(out, command=command, wait=wait):
        recover(out, hw)
        yield
