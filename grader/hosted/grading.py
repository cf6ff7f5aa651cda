"""What both hosted entrypoints share: the package's configuration, the choice of isolation,
finding the submitted notebook, and grading it through :func:`grader.grade_one.grade_one`.

Isolation modes (``--sandbox``)
    ``auto`` (default): bubblewrap where it can start (:func:`grader.sandbox.available`), else
    the container mode (:mod:`grader.kernels.container`). ``bwrap``: bubblewrap or nothing.
    ``container``: always the container mode. The mode used is stated in every result.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import json
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from functools import partial
from pathlib import Path
from typing import Any

from grader.assignment import Assignment, load_assignment
from grader.follow_through import FollowThrough
from grader.grade_one import grade_one
from grader.limits import Limits
from grader.results import StudentResult
from grader.submissions import Submission
from problems.answers import WRITTEN

MODES = ("auto", "bwrap", "container")

CONFIG = "eulertop-hosted.json"
"""The package's settings, beside the assignment folder: ``sandbox``, ``kernel_user``,
``limits`` (fields of :class:`grader.limits.Limits`), and the platform's own."""


class HostedError(Exception):
    """The grader cannot grade here (no assignment, no isolation, bad configuration); the
    message is for the instructor and goes into the platform's results."""


@dataclass(frozen=True)
class Isolation:
    """How the kernel is confined: ``mode`` (``bwrap`` or ``container``), a line for the
    results, whether the key was out of the kernel's reach, and the ``execute`` to use."""

    mode: str
    note: str
    protected: bool
    execute: Callable[..., Any]


def read_config(folder: Path) -> dict:
    """``folder/eulertop-hosted.json`` (``{}`` when absent); :class:`HostedError` if unusable."""
    path = Path(folder) / CONFIG
    if not path.is_file():
        return {}
    try:
        config = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise HostedError(f"{path}: cannot read the package's settings: {e}") from None
    if not isinstance(config, dict):
        raise HostedError(f"{path}: the package's settings are not a JSON object")
    return config


def open_package(package: Path, assignment: str, root: Path,
                 private: Sequence[Path] = ()) -> tuple[dict, Assignment, Limits]:
    """The package's settings, its assignment (``package/assignment``) and limits — after the
    package and ``private`` were made the grader's own and ``root/results`` the grader's folder
    (the notebook, run as another user, can read neither the key nor write results)."""
    from grader.kernels.container import protect

    config = read_config(package)
    protect([package, *private])
    (root / "results").mkdir(parents=True, exist_ok=True)
    (root / "results").chmod(0o755)
    return config, load_assignment(package / assignment), config_limits(config)


def config_limits(config: Mapping) -> Limits:
    """The :class:`Limits` stored in a package's settings (defaults for what is absent)."""
    try:
        return Limits(**config.get("limits", {}))
    except (TypeError, ValueError) as e:
        raise HostedError(f"{CONFIG}: bad limits: {e}") from None


def limits_dict(limits: Limits) -> dict:
    """``limits`` as plain JSON for :data:`CONFIG`."""
    return asdict(limits)


def choose_isolation(mode: str = "auto", user: str | None = None) -> Isolation:
    """The isolation of ``mode`` (:data:`MODES`); :class:`HostedError` saying why there is none."""
    from grader import sandbox
    from grader.execute import execute_submission
    from grader.kernels import container

    if mode not in MODES:
        raise HostedError(f"sandbox mode {mode!r}: expected one of {', '.join(MODES)}")
    if mode in ("auto", "bwrap"):
        found = sandbox.available()
        if found is not None:
            return Isolation("bwrap", found.describe(), True,
                             partial(execute_submission, sandbox=True))
        if mode == "bwrap":
            try:
                sandbox.probe()
            except sandbox.SandboxUnavailable as err:
                raise HostedError(str(err)) from None
    try:
        kernel_user = container.kernel_user(user)
    except container.KernelUserError as err:
        raise HostedError(str(err)) from None
    why = container.check_interpreter(kernel_user)
    if why is not None:
        raise HostedError(why)
    return Isolation("container", container.describe(kernel_user), kernel_user is not None,
                     partial(execute_submission,
                             kernel_factory=container.kernel_factory(kernel_user)))


def find_notebook(folder: Path, preferred: str | None = None) -> tuple[Path | None, str]:
    """The one submitted notebook in ``folder`` (recursively; hidden files and Jupyter's
    checkpoints ignored): ``(path, "")``, or ``(None, why not)``. Of several, the one named
    ``preferred`` is taken if there is exactly one such."""
    folder = Path(folder)
    if not folder.is_dir():
        return None, f"no submission folder {folder}"
    found = sorted(p for p in folder.rglob("*.ipynb")
                   if not any(part.startswith(".") for part in p.relative_to(folder).parts)
                   and not p.is_symlink())
    if len(found) == 1:
        return found[0], ""
    if not found:
        return None, "no notebook (.ipynb file) was submitted"
    named = [p for p in found if preferred and p.name == preferred]
    if len(named) == 1:
        return named[0], ""
    names = ", ".join(str(p.relative_to(folder)) for p in found)
    return None, f"several notebooks were submitted ({names}); submit only one"


def grade_notebook(a: Assignment, student_id: str, path: Path, limits: Limits,
                   isolation: Isolation) -> StudentResult:
    """Grade ``path`` as ``student_id``'s submission (their variant's key): its record, with
    follow-through credit where the assignment gives it (:mod:`grader.follow_through`). The
    numbers only: written answers are left to the platform's own manual grading (issue 31,
    ``docs/instructors/hosted.md``), neither read nor counted in the score."""
    expected = tuple(k for k in a.expected(student_id) if k.answer.kind != WRITTEN)
    result = grade_one(Submission(student_id, Path(path)), expected, a.key_hash(student_id),
                       limits, isolation.execute, parameters=a.parameters(student_id))
    follow = FollowThrough.of(a)
    if follow is None:
        return result
    try:
        return follow.apply(result, expected)
    finally:
        follow.close()


def env_root(variable: str, default: str) -> Path:
    """The platform's root folder: ``$variable`` if set, else ``default``."""
    return Path(os.environ.get(variable) or default)
