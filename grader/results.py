"""Result records of a grading run, and writing them so that no reader ever sees half a file.

``results/<id>.json`` holds one :class:`StudentResult`: everything the gradebook, the feedback
page and the next run's resume check need, as plain JSON that reads back to an equal record
(``StudentResult.from_dict(r.to_dict()) == r``; after otter-grader's ``TestCaseResult``).

Plain JSON, strictly
    What a student submitted is stored as the grader extracted it, except that the floats JSON
    cannot hold (NaN, ±inf) are stored as the strings ``"NaN"``, ``"Infinity"``,
    ``"-Infinity"``. The verdict was reached on the real value before that (and its message
    says what was wrong); the record only keeps it for display. This keeps every result file
    strict JSON, and makes the round trip exact (NaN never equals itself).

Atomic files
    :func:`atomic_write_text` writes a temporary file *in the same folder*, flushes it to disk,
    and renames it over the target (``os.replace``, atomic on POSIX): a reader, or the next
    run after a crash, sees the old file or the new one, never a mixture. A run killed between
    the two steps leaves a hidden ``.<name>.*.tmp`` file, which :func:`remove_stale_temporaries`
    clears at the start of the next run.

Text no file can hold
    A Python string can hold a lone surrogate (an answer ``"\\ud800"``, a file name's
    undecodable byte), which UTF-8 cannot encode. A record keeps each as its escape
    (:func:`grader.plain_text.storable`) and its message says so (:data:`UNSTORABLE`), so the
    record is written and the next run does not meet the same string again; and
    :func:`atomic_write_text` writes anything left of the kind as its escape rather than fail.

Floor 0 of grader/ (records and pure helpers; grader/API.md).
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, is_dataclass
from pathlib import Path
from typing import Any

from grader.plain_text import SURROGATE, storable
from problems.answers import Verdict

STATUSES = ("graded", "missing", "failed")
"""``graded``: executed and compared; ``missing``: no submission; ``failed``: a submission
that could not be graded (the message says why) — it earns nothing (fail closed)."""

TEMP_SUFFIX = ".tmp"
OPTIONAL = ("overridden", "submitted", "late", "reviewed")
"""Fields of a record left out of its file when empty (a record without them reads as
before)."""
_NON_FINITE = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}
UNSTORABLE = ("note: some text of this record (a submitted value, a message or a file name) "
              "held characters no file can hold (lone surrogates); each is kept as its escape, "
              "such as \\ud800")


def plain_json(value: Any) -> Any:
    """``value`` as strict JSON data: tuples become lists, non-finite floats strings.

    Examples
    --------
    >>> plain_json((1, float("nan"), {"a": (True, None)}))
    [1, 'NaN', {'a': [True, None]}]
    """
    if isinstance(value, float) and not math.isfinite(value):
        return "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
    if isinstance(value, list | tuple):
        return [plain_json(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): plain_json(v) for k, v in value.items()}
    if value is None or isinstance(value, bool | int | float | str):
        return value
    # The extractor hands over plain JSON only; anything else is shown, never interpreted.
    return repr(value)


def non_finite_read(value: Any) -> Any:
    """``value`` (a number or a list of them, as stored) with :func:`plain_json`'s spellings of
    NaN and ±inf read back as floats; anything else as it is.

    Examples
    --------
    >>> non_finite_read(["NaN", 1.5, "-Infinity"]), non_finite_read("loops")
    ([nan, 1.5, -inf], 'loops')
    """
    if isinstance(value, str) and value in _NON_FINITE:
        return _NON_FINITE[value]
    if isinstance(value, list):
        return [non_finite_read(v) for v in value]
    return value


@dataclass(frozen=True)
class AnswerResult:
    """One answer of one question, as graded.

    Attributes
    ----------
    variable : str
        The notebook variable, ``q{question}_{name}``.
    question : int
        The question number (1-based).
    name : str
        The answer's name within the question.
    submitted : Any
        What was extracted, as plain JSON (module docstring); None when not set.
    verdict : problems.answers.Verdict
        Status, points, message and recognised mistake.
    """

    variable: str
    question: int
    name: str
    submitted: Any
    verdict: Verdict

    def __post_init__(self) -> None:
        object.__setattr__(self, "submitted", plain_json(self.submitted))
        # checked once here, not again by each record made around it (:func:`_unstorable`)
        object.__setattr__(self, "_holds_surrogate", any(
            _unstorable(getattr(self, f.name)) for f in fields(self)))

    def to_dict(self) -> dict:
        """Plain JSON; ``AnswerResult.from_dict(a.to_dict()) == a``."""
        return {"variable": self.variable, "question": self.question, "name": self.name,
                "submitted": self.submitted, "verdict": self.verdict.to_dict()}

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> AnswerResult:
        """Inverse of :meth:`to_dict`."""
        return cls(variable=d["variable"], question=int(d["question"]), name=d["name"],
                   submitted=d["submitted"], verdict=Verdict.from_dict(d["verdict"]))


@dataclass(frozen=True)
class StudentResult:
    """One student's result: ``results/<id>.json``.

    Attributes
    ----------
    student_id : str
        The roster id; it came from the submission's file or folder name.
    status : str
        One of :data:`STATUSES`.
    message : str
        For people: what happened (execution problems, a metadata mismatch …); ``""`` if none.
    answers : tuple of AnswerResult
        Every answer of the student's key, in question order (all unawarded when not graded).
    points, max_points : float
        Awarded and possible points.
    submission_sha256 : str or None
        SHA-256 (hex) of the submitted file's bytes; None when missing.
    key_sha256 : str
        The student's key hash from ``key.json`` (``"sha256:…"``); resume compares both.
    execution : dict
        ``status``, ``message``, ``cell_errors`` (list), ``output_truncated``; ``{}`` when
        nothing was executed. (No duration: it would differ on every run.) ``foreign``: why
        the notebook that ran is not this assignment's, another student's (issue 30) or
        another variant's; ``variant``: the hash of the student's parameters it was graded as
        (:func:`grader.grade_one.parameters_hash`).
    sandboxed : bool
        Whether the kernel ran inside the sandbox (:mod:`grader.sandbox`); False when graded
        with ``--no-sandbox``, or when nothing was executed.
    graded_at : str
        ISO 8601 time (UTC) the record was made — the record's one volatile field: grading
        the same submissions again gives records equal in everything else.
    overridden : dict
        The instructor's overrides applied to this record (:mod:`grader.overrides`): answer
        variable, or ``"total"`` → ``{"points", "was", "reason", "by", "at"}``; ``{}`` when
        none (then absent from the file, which reads as before).
    submitted : dict
        When the submission came in and where that time came from (:mod:`grader.late`):
        ``{"at": ISO 8601 with its offset, "source": "Gradescope's submission time" …}``;
        ``{}`` when unknown (absent from the file).
    late : dict
        What the assignment's late policy made of it (:func:`grader.late.late_entry`: the due
        time that applied, how late, the percentage and points taken); ``{}`` when there is
        no policy or no time (absent from the file).
    reviewed : dict
        The reviews of its written answers applied (:mod:`grader.reviews`): variable →
        ``{"rubric": [{"item", "points", "given"}], "adjust", "comment", "by", "at"}``; ``{}``
        when none (absent from the file).
    """

    student_id: str
    status: str
    message: str
    answers: tuple[AnswerResult, ...]
    points: float
    max_points: float
    submission_sha256: str | None
    key_sha256: str
    execution: dict
    sandboxed: bool
    graded_at: str
    overridden: dict = field(default_factory=dict)
    submitted: dict = field(default_factory=dict)
    late: dict = field(default_factory=dict)
    reviewed: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {self.status!r}")
        object.__setattr__(self, "answers", tuple(self.answers))
        object.__setattr__(self, "points", float(self.points))
        object.__setattr__(self, "max_points", float(self.max_points))
        object.__setattr__(self, "execution", plain_json(self.execution))
        for name in OPTIONAL:
            object.__setattr__(self, name, plain_json(getattr(self, name)))
        if not _unstorable(self):
            return
        record = self.to_dict()
        kept = _storable(record)
        if kept != record:  # rebuilt from the storable text, saying so (module docstring)
            kept["message"] = "\n".join(filter(None, (kept["message"], UNSTORABLE)))
            clean = StudentResult.from_dict(kept)
            for f in fields(self):
                object.__setattr__(self, f.name, getattr(clean, f.name))

    def question_points(self) -> dict[int, float]:
        """Points awarded per question number (every question of the key, 0 when unawarded)."""
        totals: dict[int, float] = {}
        for a in self.answers:
            totals[a.question] = totals.get(a.question, 0.0) + a.verdict.points
        return totals

    def to_dict(self) -> dict:
        """Plain JSON; ``StudentResult.from_dict(r.to_dict()) == r``."""
        d = {f.name: getattr(self, f.name) for f in fields(self)}
        d["answers"] = [a.to_dict() for a in self.answers]
        for name in OPTIONAL:
            if not d[name]:
                del d[name]
        return d

    @classmethod
    def from_dict(cls, d: Mapping[str, Any]) -> StudentResult:
        """Inverse of :meth:`to_dict`; raises KeyError/ValueError/TypeError on a foreign file."""
        names = {f.name for f in fields(cls)}
        unknown = sorted(set(d) - names)
        if unknown:
            raise ValueError(f"unknown fields {unknown} in a result record")
        kw = {name: d[name] for name in names if name in d or name not in OPTIONAL}
        kw["answers"] = tuple(AnswerResult.from_dict(a) for a in d["answers"])
        return cls(**kw)


def _unstorable(value: Any) -> bool:
    """Whether a string anywhere in ``value`` (plain JSON, a record, its answers and verdicts)
    holds a lone surrogate: the check every record makes, without building its dict (a
    record is made several times over as a grade is settled)."""
    kind = type(value)
    if kind in _SCALARS:
        return False
    if kind is str:
        return not value.isascii() and SURROGATE.search(value) is not None
    if kind is AnswerResult:  # checked when it was made, its fields never changed since
        return value._holds_surrogate
    if kind is list or kind is tuple:
        return any(type(v) not in _SCALARS and _unstorable(v) for v in value)
    if kind is dict:
        return any(_unstorable(k) or _unstorable(v) for k, v in value.items())
    if is_dataclass(value):
        return any(_unstorable(getattr(value, f.name)) for f in fields(value))
    return False


_SCALARS = frozenset({float, int, bool, type(None)})


def _storable(value: Any) -> Any:
    """Plain JSON ``value`` with every string (keys too) :func:`~grader.plain_text.storable`."""
    if isinstance(value, str):
        return storable(value)
    if isinstance(value, list):
        return [_storable(v) for v in value]
    if isinstance(value, dict):
        return {storable(k): _storable(v) for k, v in value.items()}
    return value


def result_json(result: StudentResult) -> str:
    """The text of ``results/<id>.json`` (sorted keys, strict JSON, indented for reading)."""
    return json.dumps(result.to_dict(), sort_keys=True, indent=1, ensure_ascii=False,
                      allow_nan=False) + "\n"


def read_result(path: Path) -> StudentResult | None:
    """The record in ``path``, or None when it is absent or not a readable result."""
    try:
        return StudentResult.from_dict(json.loads(Path(path).read_text(encoding="utf-8")))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, ValueError, TypeError):
        return None


def atomic_write_text(path: Path, text: str) -> None:
    """Replace ``path`` by a file holding ``text`` as UTF-8, atomically; a lone surrogate is
    written as its escape (module docstring)."""
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=TEMP_SUFFIX, dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", errors="backslashreplace", newline="") as f:
            f.write(text)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_result(folder: Path, result: StudentResult) -> Path:
    """Write ``folder/<id>.json`` atomically; returns its path."""
    path = Path(folder) / f"{result.student_id}.json"
    atomic_write_text(path, result_json(result))
    return path


def remove_stale_temporaries(*folders: Path) -> list[Path]:
    """Delete the hidden temporary files an interrupted run left in ``folders``; the list."""
    removed = []
    for folder in folders:
        if Path(folder).is_dir():
            for p in Path(folder).glob(f".*{TEMP_SUFFIX}"):
                p.unlink(missing_ok=True)
                removed.append(p)
    return removed
