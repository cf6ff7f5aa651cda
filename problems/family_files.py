"""Families from outside the package: a file, a folder of them, installed entry points.

:func:`catalogue` is what every command uses: the built-in families
(:data:`problems.templates.FAMILIES`, in catalogue order), then those of installed packages
(the entry-point group :data:`ENTRY_POINT_GROUP`, each entry point naming a family module), then
those of the folders given (``--families DIR``, or ``families = [...]`` in an assignment spec).

A folder's families are its ``*.py`` files and its packages (sub-folders with an
``__init__.py``), in name order; names starting with ``_`` or ``.`` are skipped. Each is
imported under a private module name (``eulertop_family_<name>_<hash of its path>``), so two
folders may both hold a ``pendulum.py``, and its own relative imports work when it is a
package.

An assignment records the SHA-256 of each family file it was generated with
(``assignment.json``'s ``families``); :func:`edited_families` names those that changed since.

Any problem — a file that does not parse or fails when imported, a missing ``NAME`` or
``answers``, a ``NAME`` that is already taken — raises :class:`~problems.family.FamilyError`
with one line naming the file (and the line, where there is one).
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
import traceback
from collections.abc import Iterable, Mapping, Sequence
from importlib import metadata
from pathlib import Path
from typing import NamedTuple

from problems.family import Family, FamilyError

ENTRY_POINT_GROUP = "eulertop.families"
"""Installed packages offer families here: ``[project.entry-points."eulertop.families"]``,
``name = "package.module"`` (the module is the family)."""


def load_family_file(path: Path, origin: str | None = None) -> Family:
    """The family defined by the file ``path`` (a ``.py`` file, or a package folder); its
    ``origin`` is the path as given, unless one is given.

    Raises
    ------
    FamilyError
        Not found, a syntax error, an exception while importing it, or a broken contract.
    """
    path = Path(path)
    source = path / "__init__.py" if path.is_dir() else path
    if not source.is_file() or (not path.is_dir() and path.suffix != ".py"):
        raise FamilyError(f"{path}: not a family file (a .py file, or a folder with an "
                          "__init__.py)")
    digest = hashlib.sha256(str(path.resolve()).encode()).hexdigest()[:12]
    name = f"eulertop_family_{path.stem}_{digest}"
    spec = importlib.util.spec_from_file_location(
        name, source, submodule_search_locations=[str(path)] if path.is_dir() else None)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses and relative imports look modules up here
    try:
        spec.loader.exec_module(module)
    except SyntaxError as err:
        del sys.modules[name]
        where = f"{err.filename or source}:{err.lineno}" if err.lineno else str(source)
        raise FamilyError(f"{where}: syntax error: {err.msg}") from None
    except Exception as err:
        del sys.modules[name]
        raise FamilyError(f"{_failing_line(err, path, source)}: the family failed when "
                          f"imported: {type(err).__name__}: {err}") from None
    return Family(module, origin or str(path), source)


def _failing_line(err: BaseException, path: Path, source: Path) -> str:
    """``file:line`` of the deepest frame of the traceback inside the family's own files."""
    inside = str(path.resolve())
    frames = [f for f in traceback.extract_tb(err.__traceback__)
              if str(Path(f.filename).resolve()).startswith(inside)]
    return f"{frames[-1].filename}:{frames[-1].lineno}" if frames else str(source)


def folder_families(folder: Path) -> list[Family]:
    """The families of ``folder`` (module docstring), in name order."""
    folder = Path(folder)
    if not folder.is_dir():
        raise FamilyError(f"{folder}: no such folder of families")
    entries = sorted(p for p in folder.iterdir() if not p.name.startswith(("_", "."))
                     and ((p.suffix == ".py" and p.is_file()) or (p / "__init__.py").is_file()))
    return [load_family_file(p) for p in entries]


def entry_point_families() -> list[Family]:
    """The families installed packages declare in :data:`ENTRY_POINT_GROUP`, by name."""
    found = []
    for ep in sorted(metadata.entry_points(group=ENTRY_POINT_GROUP), key=lambda e: e.name):
        dist = ep.dist.name if ep.dist is not None else "?"
        origin = f"entry point {ep.name} ({dist})"
        try:
            module = ep.load()
        except Exception as err:
            raise FamilyError(f"{origin}: {ep.value} cannot be imported: "
                              f"{type(err).__name__}: {err}") from None
        file = getattr(module, "__file__", None)
        found.append(Family(module, origin, Path(file) if file else None))
    return found


def catalogue(folders: Sequence[Path] = (), *, entry_points: bool = True,
              builtins: Mapping[str, Family] | None = None) -> dict[str, Family]:
    """Every family by name: built-in, then installed, then from ``folders`` (in order).

    Raises
    ------
    FamilyError
        A family that cannot be loaded, or whose ``NAME`` is already taken (the message names
        both places).
    """
    if builtins is None:
        from problems.templates import FAMILIES as builtins
    families = dict(builtins)
    extra: list[Iterable[Family]] = [entry_point_families()] if entry_points else []
    extra += [folder_families(f) for f in folders]
    for group in extra:
        for family in group:
            taken = families.get(family.name)
            if taken is not None:
                what = "a built-in family" if taken.origin == "built-in" else \
                    f"already defined by {taken.where}"
                raise FamilyError(f"{family.where}: NAME {family.name!r} is {what}; "
                                  "give this family another NAME")
            families[family.name] = family
    return families


class EditedFamily(NamedTuple):
    """A family file that is not the one an assignment was generated with."""

    name: str
    path: Path  # as the manifest records it, relative to the assignment folder
    recorded: str  # its SHA-256 at generate
    now: str | None  # its SHA-256 now; None: the file is gone


def file_sha256(path: Path) -> str:
    """The hex SHA-256 of the file ``path``'s bytes (what ``assignment.json`` records)."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def edited_families(manifest: Mapping, folder: Path) -> list[EditedFamily]:
    """The family files ``manifest`` (an ``assignment.json``) records whose bytes, read
    relative to ``folder``, are no longer those it hashed at generate: edited, or gone. Families
    of installed packages are not files of the assignment's and are not checked."""
    edited = []
    for name, where in manifest.get("families", {}).items():
        if "file" not in where or "sha256" not in where:
            continue
        path = Path(folder) / where["file"]
        now = file_sha256(path) if path.is_file() else None
        if now != where["sha256"]:
            edited.append(EditedFamily(name, Path(where["file"]), where["sha256"], now))
    return edited


def with_family_hashes(manifest: Mapping, edited: Iterable[EditedFamily]) -> dict:
    """A copy of ``manifest`` recording the SHA-256 each of ``edited`` has now."""
    record = {name: dict(where) for name, where in manifest.get("families", {}).items()}
    for e in edited:
        record[e.name]["sha256"] = e.now
    return {**manifest, "families": record}
