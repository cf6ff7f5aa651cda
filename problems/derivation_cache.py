"""Symbolic derivations kept between runs as text, in the user's cache folder, under a digest
of everything the text depends on; read back only from a file the user alone can write.

The design (digest, safety, location): problems/API.md, "Symbolic derivations kept between runs".
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import stat
import sys
import tempfile
from collections.abc import Callable, Iterable
from pathlib import Path
from types import ModuleType
from typing import Any

__all__ = ["cache_folder", "kept"]

FORMAT = 1
"""Bumped when what a kept file holds changes shape."""

CACHE_ENV = "EULERTOP_CACHE_DIR"
"""A folder to keep derivations in instead of ``$XDG_CACHE_HOME/eulertop/derivations`` (or
``~/.cache/eulertop/derivations``); ``off`` keeps none."""


def cache_folder() -> Path | None:
    """Where derivations are kept: ``$EULERTOP_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/eulertop/derivations``, else ``~/.cache/eulertop/derivations``; None when
    ``EULERTOP_CACHE_DIR=off`` or there is no home folder."""
    own = os.environ.get(CACHE_ENV)
    if own:
        return None if own == "off" else Path(own)
    base = os.environ.get("XDG_CACHE_HOME")
    if not base:
        home = os.path.expanduser("~")
        if home == "~":
            return None
        base = os.path.join(home, ".cache")
    return Path(base) / "eulertop" / "derivations"


def kept(name: str, sources: Iterable[ModuleType], derive: Callable[[], Any]) -> Any:
    """``derive()`` (plain JSON: the derivation's texts), read back from the cache folder when
    kept there under the same digest (:func:`_digest` of ``name`` and ``sources``), else derived
    and kept."""
    folder = cache_folder()
    if folder is None:
        return derive()
    digest = _digest(name, sources)
    path = folder / f"{name}-{digest[:32]}.json"
    found = _read(path, digest)
    if found is not None:
        return found["value"]
    value = derive()
    with contextlib.suppress(OSError):  # not keeping it is all a failure costs
        _write(path, {"format": FORMAT, "digest": digest, "value": value})
        for old in folder.glob(f"{name}-*.json"):  # the digests kept before under this name
            if old != path:
                old.unlink(missing_ok=True)
    return value


def _digest(name: str, sources: Iterable[ModuleType]) -> str:
    """SHA-256 of what a derivation's texts depend on: ``name``, the files of
    :func:`_source_files`, and the versions of Python and sympy (with its ground types, which
    decide how polynomials are worked out)."""
    import sympy
    from sympy.external.gmpy import GROUND_TYPES

    h = hashlib.sha256(json.dumps([FORMAT, name, sys.version_info[:2], sympy.__version__,
                                   GROUND_TYPES]).encode())
    for file in _source_files(sources):
        data = file.read_bytes()
        h.update(f"\n{file.name} {len(data)}\n".encode())
        h.update(data)
    return h.hexdigest()


def _source_files(sources: Iterable[ModuleType]) -> list[Path]:
    """The source files of ``sources`` and of every module of :mod:`solver` (whose
    :mod:`solver.symbolic` derives), in a fixed order."""
    import solver

    files = {Path(m.__file__) for m in sources}
    files.update(Path(solver.__file__).parent.glob("*.py"))
    return sorted(files)


def _read(path: Path, digest: str) -> dict | None:
    """The kept record at ``path`` if it is safe to read (:func:`_safe`) and holds ``digest``;
    None otherwise."""
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        if not (_safe(os.fstat(fd)) and _safe(os.stat(path.parent))):
            return None
        with os.fdopen(fd, "rb", closefd=False) as file:
            record = json.loads(file.read())
    except (OSError, ValueError):
        return None
    finally:
        os.close(fd)
    ok = isinstance(record, dict) and record.get("format") == FORMAT \
        and record.get("digest") == digest and "value" in record
    return record if ok else None


def _safe(status: os.stat_result) -> bool:
    """Whether a file or folder is the user's alone: owned by them, not writable by group or
    others (a symbolic link is never opened: ``O_NOFOLLOW``)."""
    return status.st_uid == os.geteuid() and not status.st_mode & (stat.S_IWGRP | stat.S_IWOTH)


def _write(path: Path, record: dict) -> None:
    """Keep ``record`` at ``path``, in a folder of the user's alone: written whole, then renamed
    into place (a reader never sees half of it). OSError where it cannot be."""
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    fd, temporary = tempfile.mkstemp(dir=path.parent, prefix=".", suffix=".tmp")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as file:
            json.dump(record, file, ensure_ascii=False)
        os.replace(temporary, path)
    except BaseException:
        os.unlink(temporary)
        raise
