"""``eulertop generate``: a roster and a list of problem families (or an assignment spec) → one
assignment folder.

Layout (``docs/instructors/generate.md`` says it for the instructor)::

    HW/assignment.json          manifest: title, seed, problems, roster, generator version, and
                                every student's reroll count and *resolved* questions (params,
                                every drawn parameter, statement, public answer spec) — no
                                answer values; with a spec also its questions' settings, the
                                spec's SHA-256, and the families from outside the package used
    HW/assignment.toml          with a spec: a copy of it
    HW/key.json                 instructor-only: every student's answers (Answer.to_dict()),
                                per question, and a content hash per student
    HW/release/<id>.ipynb       what the student gets
    HW/solutions/<id>.ipynb     the same with the key's answers filled in

Seeding
    Question ``k`` of student ``id`` is ``families[family].generate(rng, settings)`` with ``rng``
    seeded by SHA-256 of ``(assignment seed, id, k, family, reroll count)``
    (:func:`variant_seed`), the family of a pool chosen the same way (:func:`pool_member`): stable
    across runs, machines and Python versions, independent of roster order and of the other
    students. numpy does not promise that every distribution draws the same numbers in every
    future version, and templates change; that is why the manifest stores the resolved
    parameters and statements, so an assignment, once generated, is what it is.

Determinism
    JSON is written with sorted keys, Python's shortest round-trip float ``repr`` and one line
    per student (:func:`json_text`); notebook cell ids are fixed names. The same inputs give
    byte-identical files. Without ``--seed`` a fresh seed is drawn, reported, and stored in the
    manifest.

Atomicity and existing folders
    Inputs are checked before anything is written. Files are written into a temporary folder
    beside ``HW`` which replaces ``HW`` by ``rename`` at the end; on any failure it is removed,
    so there is never half an assignment. An existing ``HW`` is refused unless ``force``;
    ``force`` replaces only a folder this generator wrote (``assignment.json``, ``key.json``,
    ``assignment.toml``, ``release/``, ``solutions/``) and refuses one holding anything else
    (``graded/``, or a wrong ``--out``). Replacing keeps the old seed when none is given and
    keeps every remaining student's reroll count when seed and questions are unchanged — so
    re-running with a roster
    that gained a student adds that student and leaves everybody else's files byte-identical.

Rerolls (:func:`reroll_students`)
    ``--reroll ID`` works on an existing ``HW`` (no ``force`` needed, no roster, seed, problems
    or title: those are the manifest's): it bumps the student's reroll count, draws their
    questions afresh with the current families (and the spec's recorded settings), and
    rewrites their two notebooks and their
    entries in ``assignment.json`` and ``key.json``. Every other file and entry — including
    anything else in ``HW`` such as ``graded/`` — is kept byte for byte; the student's key hash
    changes, which tells the grader their results are stale.
"""

from __future__ import annotations

import gc
import hashlib
import json
import os
import secrets
import shutil
import tempfile
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from importlib import metadata
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from problems.answers import Answer
from problems.deadlines import LatePolicy
from problems.family import Family, FamilyError
from problems.notebook import DEFAULT_INSTALL, notebook_texts
from problems.roster import Roster
from problems.settings import QuestionSettings
from problems.variant import Variant, variable_name
from problems.written import WRITTEN_QUESTION, Written, written_variant

FORMAT_VERSION = 1
ASSIGNMENT = "assignment.json"
KEY = "key.json"
RELEASE = "release"
SOLUTIONS = "solutions"
SPEC_COPY = "assignment.toml"
OWNED = frozenset({ASSIGNMENT, KEY, RELEASE, SOLUTIONS, SPEC_COPY})

Progress = Callable[[int, int], None]


class GenerateError(ValueError):
    """Bad input to the generator (unknown problem, existing folder …); nothing was written."""


class TemplateError(RuntimeError):
    """A template failed or returned something that is not a valid Variant; nothing was written."""


class Question(NamedTuple):
    """One question of an assignment: its family, or the pool each student gets one family
    of, and what a spec changes in it; or (no pool) a spec's question that is only a written
    part, ``written``, under its ``title`` (:func:`problems.written.written_variant`).

    ``label`` is what the manifest's ``problems`` lists: the family's name, the pool's
    names joined by ``|``, or ``written:<name>``.
    """

    label: str
    pool: tuple[str, ...]
    settings: QuestionSettings | None = None
    written: Written | None = None
    title: str | None = None

    @classmethod
    def of(cls, family: str) -> Question:
        """The plain question of one family (``--problems``)."""
        return cls(family, (family,))

    def record(self) -> dict:
        """Plain JSON for the manifest (:meth:`from_record` reads it back)."""
        settings = None if self.settings is None else self.settings.to_dict()
        d = {"label": self.label, "pool": list(self.pool), "settings": settings}
        if self.written is not None:
            d.update(written=self.written.record(), title=self.title)
        return d

    @classmethod
    def from_record(cls, d: Mapping) -> Question:
        settings = d.get("settings")
        written = d.get("written")
        return cls(d["label"], tuple(d["pool"]),
                   None if settings is None else QuestionSettings.from_dict(settings),
                   None if written is None else Written.from_record(written), d.get("title"))


@dataclass(frozen=True)
class Summary:
    """What a generate or reroll run did, for the command line to report."""

    out: Path
    seed: int
    problems: tuple[str, ...]
    students: tuple[str, ...]  # the students whose files were (re)written
    notes: tuple[str, ...] = ()


def generator_version() -> str:
    """The installed eulertop version, recorded in the manifest."""
    try:
        return metadata.version("eulertop")
    except metadata.PackageNotFoundError:
        return "0+unknown"


_SEED_JSON = json.JSONEncoder(ensure_ascii=False, separators=(",", ":"))
"""What ``json.dumps(payload, ensure_ascii=False, separators=(",", ":"))`` encodes with, made
once: the text hashed into a student's seeds (:func:`variant_seed`, :func:`pool_member`)."""


def variant_seed(seed: int, student_id: str, question: int, family: str, reroll: int = 0) -> int:
    """The 256-bit integer seeding one student's question (stable everywhere; no ``hash()``).

    Examples
    --------
    >>> variant_seed(1, "alice", 1, "rod") == variant_seed(1, "alice", 1, "rod")
    True
    >>> variant_seed(1, "alice", 1, "rod") == variant_seed(1, "alice", 1, "rod", reroll=1)
    False
    """
    return int.from_bytes(_variant_digest(seed, student_id, question, family, reroll), "big")


def _variant_digest(seed: int, student_id: str, question: int, family: str, reroll: int) -> bytes:
    """The SHA-256 digest whose big-endian integer is :func:`variant_seed`."""
    payload = _SEED_JSON.encode(
        ["eulertop-variant", 1, int(seed), student_id, int(question), family, int(reroll)])
    return hashlib.sha256(payload.encode("utf-8")).digest()


def variant_rng(
    seed: int, student_id: str, question: int, family: str, reroll: int = 0
) -> np.random.Generator:
    """A fresh ``numpy.random.Generator`` for one student's question (see :func:`variant_seed`):
    ``default_rng(variant_seed(…))``, seeded with the integer's 32-bit words as numpy reads an
    integer (least significant first, no leading zero word) — a third cheaper than the int."""
    return np.random.default_rng(
        seed_words(_variant_digest(seed, student_id, question, family, reroll)))


def seed_words(digest: bytes) -> np.ndarray:
    """The big-endian integer of ``digest`` as numpy's ``SeedSequence`` reads an integer:
    its 32-bit words, least significant first, without leading zero words (one word for 0)."""
    words = np.frombuffer(digest[::-1], dtype="<u4")
    top = len(words)
    while top > 1 and words[top - 1] == 0:
        top -= 1
    return words[:top]


def pool_member(pool: Sequence[str], seed: int, student_id: str, question: int,
                reroll: int = 0) -> str:
    """The family of ``pool`` that student ``student_id`` gets as question ``question``: from
    SHA-256 of ``(seed, id, question, pool, reroll)``, like :func:`variant_seed`.

    Examples
    --------
    >>> pool_member(["a", "b"], 1, "alice", 2) == pool_member(["a", "b"], 1, "alice", 2)
    True
    >>> pool_member(["only"], 1, "alice", 2)
    'only'
    """
    if len(pool) == 1:  # what the hash below gives (any number modulo 1 is 0), without it
        return pool[0]
    payload = _SEED_JSON.encode(
        ["eulertop-pool", 1, int(seed), student_id, int(question), list(pool), int(reroll)])
    digest = int.from_bytes(hashlib.sha256(payload.encode("utf-8")).digest(), "big")
    return pool[digest % len(pool)]


def resolve_problems(
    names: Sequence[str] | None, families: Mapping[str, Family]
) -> tuple[str, ...]:
    """The problem list: ``names`` checked against ``families``, or all of them in order.

    A name may repeat (two variants of one family). Raises :class:`GenerateError` naming the
    unknown names and listing the known ones.
    """
    if not families:
        raise GenerateError("no problem families are registered (problems.templates.CATALOGUE)")
    if names is None:
        return tuple(families)
    names = tuple(n.strip() for n in names)
    if not names or "" in names:
        raise GenerateError("--problems: empty problem name (give a comma-separated list)")
    unknown = [n for n in names if n not in families]
    if unknown:
        raise GenerateError(
            f"--problems: unknown problem {', '.join(map(repr, unknown))}; "
            f"known: {', '.join(families)}"
        )
    return names


def student_variants(
    families: Mapping[str, Family],
    questions: Sequence[Question | str],
    seed: int,
    student_id: str,
    reroll: int = 0,
) -> tuple[Variant, ...]:
    """Draw one student's questions (a plain family name stands for its :class:`Question`);
    a failing or misbehaving family raises TemplateError."""
    variants = []
    for k, question in enumerate(questions, start=1):
        question = Question.of(question) if isinstance(question, str) else question
        if question.written is not None:
            variants.append(written_variant(question.written, question.title))
            continue
        name = pool_member(question.pool, seed, student_id, k, reroll)
        variants.append(_one_variant(families, question, k, name, seed, student_id, reroll))
    return tuple(variants)


def class_variants(
    families: Mapping[str, Family],
    questions: Sequence[Question | str],
    seed: int,
    student_ids: Sequence[str],
    rerolls: Mapping[str, int],
) -> list[tuple[Variant, ...]]:
    """:func:`student_variants` of each student — the same variants — question by question:
    a family with a batch form draws and solves all the students it is given at once
    (:meth:`Family.generate_many`), the others are drawn one student at a time."""
    drawn: dict[str, list[Variant]] = {sid: [] for sid in student_ids}
    for k, question in enumerate(questions, start=1):
        question = Question.of(question) if isinstance(question, str) else question
        if question.written is not None:  # a written part alone: nothing drawn
            for sid in student_ids:
                drawn[sid].append(written_variant(question.written, question.title))
            continue
        by_family: dict[str, list[str]] = {}
        for sid in student_ids:
            name = pool_member(question.pool, seed, sid, k, rerolls.get(sid, 0))
            by_family.setdefault(name, []).append(sid)
        for name, sids in by_family.items():
            variants = _question_variants(families, question, k, name, seed, sids, rerolls)
            for sid, variant in zip(sids, variants, strict=True):
                drawn[sid].append(variant)
    return [tuple(drawn[sid]) for sid in student_ids]


def _question_variants(families: Mapping[str, Family], question: Question, k: int, name: str,
                       seed: int, sids: Sequence[str], rerolls: Mapping[str, int]
                       ) -> list[Variant]:
    """Question ``k`` of family ``name`` for the students ``sids``: drawn together by a family
    with a batch form (:meth:`Family.generate_many`; a failure is a TemplateError naming the
    question and the students), else one student at a time (one naming the student)."""
    family = families[name]
    if not family.batched:
        return [_one_variant(families, question, k, name, seed, sid, rerolls.get(sid, 0))
                for sid in sids]
    where = f"template {name!r}, question {k}, students {sids[0]!r} to {sids[-1]!r}"
    try:
        rngs = [variant_rng(seed, sid, k, name, rerolls.get(sid, 0)) for sid in sids]
        variants = family.generate_many(rngs, question.settings)
    except Exception as e:
        raise TemplateError(f"{where} (drawn together) failed: {type(e).__name__}: {e}") from e
    for sid, variant in zip(sids, variants, strict=True):
        _check_variant(variant, name, f"template {name!r}, student {sid!r}, question {k}")
    return variants


def _one_variant(families: Mapping[str, Family], question: Question, k: int, name: str,
                 seed: int, student_id: str, reroll: int) -> Variant:
    """Question ``k`` of ``student_id`` from family ``name``; TemplateError naming them."""
    where = f"template {name!r}, student {student_id!r}, question {k}"
    try:
        rng = variant_rng(seed, student_id, k, name, reroll)
        variant = families[name].generate(rng, question.settings)
    except Exception as e:
        raise TemplateError(f"{where} failed: {type(e).__name__}: {e}") from e
    _check_variant(variant, name, where)
    return variant


def _check_variant(variant: Any, name: str, where: str) -> None:
    if not isinstance(variant, Variant) or variant.family != name:
        raise TemplateError(f"{where}: generate() must return a Variant of family {name!r}")


def _compact(obj: Any) -> str:
    return json.dumps(obj, sort_keys=True, ensure_ascii=False, allow_nan=False)


_ENTRY_JSON = json.JSONEncoder(sort_keys=True, ensure_ascii=False, allow_nan=False,
                               check_circular=False)
""":func:`_compact`'s encoding, by an encoder made once, for the entries the generator builds
fresh (trees, never cycles: no check for one, which costs ~10 % of encoding a student's
entries): worker processes hand back each student's entries so, in UTF-8
(:func:`student_entries`), which :func:`json_pieces` writes as they are — cheaper to send
between processes than the nested dicts, and encoded in parallel rather than by the parent at
the end."""


def json_text(document: Mapping[str, Any]) -> str:
    """Deterministic JSON for the manifest and the key: one line per top-level field, and one
    line per student under ``"students"``.

    Keys are sorted and floats written by Python's shortest round-trip ``repr``. A student per
    line keeps a reroll's change to one line (diff-friendly), and lets json use its C encoder:
    ``indent`` would select the pure-Python one, several times slower on a class of 300.
    """
    return "".join(json_pieces(document))


def json_pieces(document: Mapping[str, Any]) -> Iterator[str | bytes]:
    """:func:`json_text` in pieces, each student's entry one of them as it is: written one by
    one (:func:`_write_json`), a class's files are never copied whole in memory. An entry
    already encoded (``bytes``, UTF-8, as worker processes hand them back) stays bytes: only
    :func:`_write_json` is given such entries."""
    yield "{\n"
    for i, name in enumerate(sorted(document)):
        value = document[name]
        if i:
            yield ",\n"
        if name == "students" and value:
            yield ' "students": {\n'
            for j, sid in enumerate(sorted(value)):
                if j:
                    yield ",\n"
                yield f"  {_compact(sid)}: "
                yield _entry_text(value[sid])
            yield "\n }"
        else:
            yield f" {_compact(name)}: {_compact(value)}"
    yield "\n}\n"


def _entry_text(entry: Any) -> str | bytes:
    return entry if isinstance(entry, bytes) else _compact(entry)


def key_hash(questions: Sequence[Mapping]) -> str:
    """``"sha256:<hex>"`` of a student's key entry ``questions`` (:func:`canonical_hash`).

    The grader recomputes it to detect that a student's key changed (a reroll, a regeneration).
    """
    return canonical_hash(questions)


def canonical_hash(value: Any) -> str:
    """``"sha256:<hex>"`` of a plain-JSON value in canonical compact JSON (keys sorted)."""
    canonical = json.dumps(
        value, sort_keys=True, separators=(",", ":"), ensure_ascii=False, allow_nan=False
    )
    return "sha256:" + hashlib.sha256(canonical.encode("utf-8")).hexdigest()


def key_entry(variants: Sequence[Variant], *, hashed: bool = True) -> dict:
    """One student's entry in ``key.json``: answers per question, and their hash (left out
    unless ``hashed``)."""
    questions = _key_questions(variants)
    return {"hash": key_hash(questions), "questions": questions} if hashed else \
        {"questions": questions}


def _key_questions(variants: Sequence[Variant], copy: bool = True) -> list[dict]:
    """:func:`key_entry`'s ``questions``; ``copy=False`` shares the answers' values (for
    encoding them at once, :meth:`problems.answers.Answer.to_dict`)."""
    return [{"question": k, "family": v.family,
             "answers": [a.to_dict(copy=copy) for a in v.answers]}
            for k, v in enumerate(variants, start=1)]


_MARK = "\x00"
"""Marks after json's separators: json escapes every control character inside a string, so in
its text (and in its UTF-8, where no other character has a zero byte) this can only be the
separators' (:func:`key_entry_text`)."""
_MARKED = json.JSONEncoder(sort_keys=True, ensure_ascii=False, allow_nan=False,
                           check_circular=False, separators=("," + _MARK, ":" + _MARK))


def key_entry_text(variants: Sequence[Variant]) -> str:
    """:func:`key_entry` encoded as :func:`json_text` writes it (:func:`key_entry_bytes`)."""
    return key_entry_bytes(variants).decode("utf-8")


def key_entry_bytes(variants: Sequence[Variant]) -> bytes:
    """:func:`key_entry_text` in UTF-8, the questions encoded once for both the entry
    (``", "``, ``": "``) and its hash (``","``, ``":"``) — the floats' ``repr`` is most of
    json's time here."""
    marked = _MARKED.encode(_key_questions(variants, copy=False)).encode("utf-8")
    mark = _MARK.encode()
    digest = hashlib.sha256(marked.replace(mark, b"")).hexdigest().encode()
    return b'{"hash": "sha256:' + digest + b'", "questions": ' + marked.replace(mark, b" ") \
        + b"}"


def manifest_entry(variants: Sequence[Variant], reroll: int) -> dict:
    """One student's entry in ``assignment.json``: reroll count and public questions."""
    return {"reroll": reroll, "questions": [v.public_dict(k) for k, v in enumerate(variants, 1)]}


def key_records(key: Mapping, student_id: str) -> Iterator[tuple[str, int, Answer]]:
    """``(variable, question, Answer)`` of a student's answers in a loaded ``key.json``, in
    question order; ``variable`` is the notebook's name (``q3_beta1``)."""
    for q in key["students"][student_id]["questions"]:
        for a in q["answers"]:
            yield variable_name(q["question"], a["name"]), int(q["question"]), Answer.from_dict(a)


def student_answers(key: Mapping, student_id: str) -> dict[str, Answer]:
    """A student's answers from a loaded ``key.json``, by notebook variable (``q3_beta1``)."""
    return {variable: answer for variable, _, answer in key_records(key, student_id)}


def _write_student(
    folder: Path, title: str, row: Mapping[str, str], variants: Sequence[Variant],
    validate: bool = True, families: Mapping[str, Family] | None = None,
    install: str | None = None,
) -> None:
    """Write a student's release and solutions notebooks; ``validate`` checks them against the
    nbformat schema (:func:`problems.notebook.notebook_texts`); ``install``: what their first
    cell says to install for the check (default :data:`problems.notebook.DEFAULT_INSTALL`)."""
    texts = notebook_texts(title, row, variants, families, install or DEFAULT_INSTALL,
                           validate=validate)
    for sub, text in zip((RELEASE, SOLUTIONS), texts, strict=True):
        _write_bytes(folder / sub / f"{row['id']}.ipynb", text.encode("utf-8"))


def _write_bytes(path: Path, data: bytes) -> None:
    """``path.write_bytes(data)`` without a Python file object and its buffer: a class's
    notebooks are hundreds of files, each written at once."""
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
    try:
        view = memoryview(data)
        while view:  # os.write may write less than asked
            view = view[os.write(fd, view):]
    finally:
        os.close(fd)


PARALLEL_MIN = 16
"""Fewer students than this are generated in this process (forking would cost more)."""

BATCH = 200
"""Most students drawn together (each question of theirs by one :meth:`Family.generate_many`
per family with a batch form) and handed to a worker process at once. A batch form's solver
calls cost 1–8 ms each whatever their size (numpy's per-call work on small arrays): over 32
students that was 1.5 ms a student; the objects of 200 students' variants take ~20 MB."""

MIN_BATCH = 8
"""Fewest students a worker process is given at once (fewer would not pay for the worker)."""

_FORKED: dict = {}
"""What worker processes inherit by ``fork`` (family modules cannot be pickled)."""


def _batch_files(
    task: tuple[Path, str, Sequence[Mapping[str, str]], Mapping[str, int], bool],
) -> list[tuple[bytes, bytes]]:
    """In a worker process (or this one): draw a batch of students' questions together, write
    their notebooks into the staging folder (the first one's schema-checked when the task says
    so) and return each one's manifest and key entries, encoded in UTF-8, in the batch's order
    (bytes cross between processes at a fifth of the cost of text: no UTF-8 to decode)."""
    tmp, title, rows, rerolls, validate = task
    families, questions, seed = _FORKED["families"], _FORKED["questions"], _FORKED["seed"]
    with _collector_paused():
        drawn = class_variants(families, questions, seed, [row["id"] for row in rows], rerolls)
        entries = []
        for i, (row, variants) in enumerate(zip(rows, drawn, strict=True)):
            _write_student(tmp, title, row, variants, validate and i == 0, families,
                           _FORKED.get("install"))
            entries.append(student_entries(variants, rerolls.get(row["id"], 0)))
        # freed while the collector is off, so that turned on again it has no batch's worth of
        # records to walk through
        del drawn
    return entries


def student_entries(variants: Sequence[Variant], reroll: int) -> tuple[bytes, bytes]:
    """A student's entries in ``assignment.json`` and ``key.json``, encoded in UTF-8
    (:func:`manifest_entry`, :func:`key_entry_bytes`)."""
    return (_ENTRY_JSON.encode(manifest_entry(variants, reroll)).encode("utf-8"),
            key_entry_bytes(variants))


@contextmanager
def _collector_paused() -> Iterator[None]:
    """Python's cycle collector off for one batch (at most :data:`BATCH` students, whose
    objects are nearly all freed by reference counting): its passes over the many small
    records drawing makes cost ~5 % of the time. Collected as usual afterwards."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def _batch_tasks(tmp: Path, title: str, rows: Sequence[Mapping[str, str]],
                 rerolls: Mapping[str, int], workers: int = 1) -> list[tuple]:
    """The roster in batches of at most :data:`BATCH`, as many for each worker and as even as
    can be (the first student's notebooks schema-checked)."""
    count = workers * max(1, -(-len(rows) // (workers * BATCH)))
    size = max(1, -(-len(rows) // count))
    return [(tmp, title, tuple(rows[i:i + size]), rerolls, i == 0)
            for i in range(0, len(rows), size)]


def _students_in_parallel(
    tmp: Path, title: str, rows: Sequence[Mapping[str, str]], rerolls: Mapping[str, int],
    families: Mapping[str, Family], questions: Sequence[Question], seed: int, jobs: int,
    install: str | None = None,
) -> Iterator[tuple[bytes, bytes]]:
    """``(manifest entry, key entry)`` of each row, in roster order, computed by ``jobs``
    forked processes that each draw batches of students and write their notebooks
    (:func:`_batch_files`).

    Every student's questions depend only on (seed, id, question, family, reroll), and each
    file is written by exactly one process, so the files are byte-identical to a serial run.
    """
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    prepare_families(families, questions)  # once here, inherited by every worker
    _FORKED.update(families=families, questions=tuple(questions), seed=seed, install=install)
    gc.freeze()  # the workers' collector skips what they inherit (and leaves its pages shared)
    try:
        with ProcessPoolExecutor(jobs, mp_context=multiprocessing.get_context("fork")) as pool:
            for entries in pool.map(_batch_files, _batch_tasks(tmp, title, rows, rerolls, jobs)):
                yield from entries
    finally:
        gc.unfreeze()
        _FORKED.clear()


def prepare_families(families: Mapping[str, Family],
                     questions: Sequence[Question | str]) -> None:
    """Call the optional ``prepare()`` of each family the questions may draw (its one-time
    work, such as sympy derivations, which drawing would otherwise do on first use in every
    worker)."""
    names = [n for q in questions for n in ((q,) if isinstance(q, str) else q.pool)]
    for name in dict.fromkeys(names):
        try:
            families[name].prepare()
        except Exception as e:
            raise TemplateError(f"template {name!r}: prepare() failed: "
                                f"{type(e).__name__}: {e}") from e


def _parallel_jobs(jobs: int | None, students: int) -> int:
    """Worker processes for ``students``: 1 (this process) for a small class or without
    ``fork``; else ``jobs`` (default: the cores this process may use)."""
    import multiprocessing

    if students < PARALLEL_MIN or "fork" not in multiprocessing.get_all_start_methods():
        return 1
    if jobs is None:
        jobs = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
            os.cpu_count() or 1
    return max(1, min(jobs, -(-students // MIN_BATCH)))


def _write_json(folder: Path, manifest: dict, key: dict) -> None:
    for name, document in ((ASSIGNMENT, manifest), (KEY, key)):
        with open(folder / name, "wb") as file:
            file.writelines(p if type(p) is bytes else p.encode("utf-8")
                            for p in json_pieces(document))
    os.chmod(folder / KEY, 0o600)  # the key is the instructor's alone


def _read_json(path: Path) -> dict:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as e:
        raise GenerateError(f"{path}: cannot read: {e}") from None


def _existing_assignment(out: Path, force: bool) -> dict | None:
    """Check the target folder; the old manifest when ``force`` replaces one, else None."""
    if not out.exists() and not out.is_symlink():
        return None
    if not out.is_dir():
        raise GenerateError(f"--out {out}: exists and is not a folder")
    if not force:
        raise GenerateError(
            f"--out {out}: already exists; pass --force to replace it, "
            "or --reroll ID to give one student a new variant"
        )
    extra = sorted(set(os.listdir(out)) - OWNED)
    if extra:
        raise GenerateError(
            f"--out {out}: --force replaces only a folder written by 'eulertop generate', "
            f"but it also holds {', '.join(extra)}; move them away or choose another --out"
        )
    return _read_json(out / ASSIGNMENT) if (out / ASSIGNMENT).exists() else None


class _Staging:
    """A temporary folder beside ``out`` that becomes ``out`` on success, vanishes on failure."""

    def __init__(self, out: Path) -> None:
        self.out = out

    def __enter__(self) -> Path:
        self.out.parent.mkdir(parents=True, exist_ok=True)
        self.tmp = Path(tempfile.mkdtemp(
            prefix=f".{self.out.name}.", suffix=".eulertop-tmp", dir=self.out.parent
        ))
        return self.tmp

    def __exit__(self, exc_type, exc, tb) -> None:
        if exc_type is None:
            try:
                self._publish()
                return
            except BaseException:
                shutil.rmtree(self.tmp, ignore_errors=True)
                raise
        shutil.rmtree(self.tmp, ignore_errors=True)

    def _publish(self) -> None:
        # mkdtemp made the folder private while the key was written into it; the finished
        # folder gets the usual permissions (key.json alone stays private).
        umask = os.umask(0o022)
        os.umask(umask)
        os.chmod(self.tmp, 0o777 & ~umask)
        if not self.out.exists():
            os.rename(self.tmp, self.out)
            return
        # A folder cannot be renamed over a non-empty one: move the old one aside first, and
        # back if the new one cannot take its place.
        old = Path(f"{self.tmp}-old")
        os.rename(self.out, old)
        try:
            os.rename(self.tmp, self.out)
        except BaseException:
            os.rename(old, self.out)
            raise
        shutil.rmtree(old)


def generate_assignment(
    roster: Roster,
    out: Path,
    families: Mapping[str, Family],
    *,
    problems: Sequence[str] | None = None,
    questions: Sequence[Question] | None = None,
    spec_file: Path | None = None,
    seed: int | None = None,
    title: str | None = None,
    follow_through: float | None = None,
    late: LatePolicy | None = None,
    install: str | None = None,
    force: bool = False,
    progress: Progress | None = None,
    jobs: int | None = None,
) -> Summary:
    """Generate an assignment folder ``out`` (layout, seeding, ``force``: module docstring).

    The questions are ``problems`` (family names; default: every family), or ``questions``
    (from an assignment spec, :mod:`problems.spec`: pools, parameters, points, tolerances),
    whose file ``spec_file`` is copied into ``out`` as :data:`SPEC_COPY`.

    ``follow_through`` (0 to 1; the spec's setting) is recorded in the manifest as the fraction
    of points an answer that follows from the student's own wrong earlier answer earns
    (:mod:`grader.follow_through`; absent: 1.0, 0: none). ``late`` (the spec's ``[late]``)
    is recorded as the manifest's ``late`` (:meth:`problems.deadlines.LatePolicy.record`).

    ``install`` (the spec's ``[student] install``) is what each notebook's first cell tells the
    student to ``%pip install`` for the check (default
    :data:`problems.notebook.DEFAULT_INSTALL`), recorded in the manifest as
    ``student_install`` for ``--reroll``.

    ``jobs`` processes draw the students' questions and write their notebooks (default: one
    per usable core, from :data:`PARALLEL_MIN` students on); the files are byte-identical to
    those of ``jobs=1``. The workers are forked (Linux, macOS) after the families' one-time work
    (:func:`prepare_families`: sympy derivations) is done here, so they inherit it instead of
    each repeating it. Where ``fork`` is not available (Windows) everything runs in this
    process, and each family does its one-time work on first use, once.

    Raises
    ------
    GenerateError
        Unknown problem, no families, ``out`` exists (without ``force``, or holding foreign
        files). Nothing is written.
    TemplateError
        A template failed; nothing is written (the temporary folder is removed).
    """
    out = Path(out)
    questions = _asked(problems, questions, families)
    old = _existing_assignment(out, force)
    notes: list[str] = []
    seed = _seed(old, seed, notes)
    rerolls = _kept_rerolls(old, seed, questions, roster, notes)
    title = out.name if title is None else title
    manifest = _new_manifest(title, seed, questions, roster, follow_through,
                             _outside_families(families, questions, out))
    if late is not None:
        manifest["late"] = late.record()
    if install is not None:
        manifest["student_install"] = install
    key = {"format": "eulertop-key", "format_version": FORMAT_VERSION, "title": title,
           "seed": seed, "students": {}}
    plan = _Plan(title, seed, questions, families, rerolls, install)
    with _Staging(out) as tmp:
        _copy_spec(spec_file, tmp, manifest)
        entries = _student_entries(tmp, plan, roster.rows, jobs)
        _record_students(roster.rows, entries, manifest, key, progress)
        _write_json(tmp, manifest, key)
    return Summary(out, seed, _labels(questions), roster.ids, tuple(notes))


@dataclass(frozen=True)
class _Plan:
    """What every student's questions are drawn from: the assignment's title, seed, questions
    and families, and the reroll count of each student who has one."""

    title: str
    seed: int
    questions: tuple[Question, ...]
    families: Mapping[str, Family]
    rerolls: Mapping[str, int]
    install: str | None = None  # what the first cell says to install for the check


def _asked(problems: Sequence[str] | None, questions: Sequence[Question] | None,
           families: Mapping[str, Family]) -> tuple[Question, ...]:
    """The questions: a spec's, else one per family of ``problems`` (default: every one)."""
    if questions is None:
        return tuple(Question.of(n) for n in resolve_problems(problems, families))
    return tuple(questions)


def _labels(questions: Sequence[Question]) -> tuple[str, ...]:
    """The manifest's ``problems``: each question's family, or its pool's names."""
    return tuple(q.label for q in questions)


def _seed(old: Mapping | None, seed: int | None, notes: list[str]) -> int:
    """``seed``, else the replaced assignment's, else a fresh one; a note says which."""
    if seed is not None:
        return seed
    seed = old["seed"] if old else secrets.randbelow(2**32)
    notes.append(f"seed {seed} ({'kept from the replaced assignment' if old else 'drawn'}; "
                 f"pass --seed {seed} to reproduce)")
    return seed


def _kept_rerolls(old: Mapping | None, seed: int, questions: Sequence[Question],
                  roster: Roster, notes: list[str]) -> dict[str, int]:
    """The reroll counts of the replaced assignment, kept when it is regenerated alike (same
    seed, problems and questions); a note names the students of the roster they are kept
    for."""
    if not old or old.get("seed") != seed or tuple(old.get("problems", ())) != _labels(questions) \
            or old.get("questions") != _questions_record(questions):
        return {}
    rerolls = {sid: s["reroll"] for sid, s in old["students"].items() if s["reroll"]}
    kept = sorted(set(rerolls) & set(roster.ids))
    if kept:
        notes.append(f"kept the reroll counts of {', '.join(kept)}")
    return rerolls


def _new_manifest(title: str, seed: int, questions: Sequence[Question], roster: Roster,
                  follow_through: float | None, outside: Mapping[str, dict]) -> dict:
    """``assignment.json`` before its students: what was asked, of whom, and from where."""
    manifest = {
        "format": "eulertop-assignment",
        "format_version": FORMAT_VERSION,
        "generator": {"name": "eulertop", "version": generator_version()},
        "title": title,
        "seed": seed,
        "problems": list(_labels(questions)),
        "roster": roster.to_dict(),
        "students": {},
    }
    planned = _questions_record(questions)
    if planned is not None:
        manifest["questions"] = planned
    if follow_through is not None:
        manifest["follow_through"] = follow_through
    if outside:
        manifest["families"] = outside
    return manifest


def _copy_spec(spec_file: Path | None, folder: Path, manifest: dict) -> None:
    """Copy the spec into ``folder`` as :data:`SPEC_COPY`, recorded with its SHA-256."""
    if spec_file is None:
        return
    data = Path(spec_file).read_bytes()
    (folder / SPEC_COPY).write_bytes(data)
    manifest["spec"] = {"file": SPEC_COPY, "sha256": hashlib.sha256(data).hexdigest()}


def _student_entries(tmp: Path, plan: _Plan, rows: Sequence[Mapping[str, str]],
                     jobs: int | None) -> Iterator[tuple[bytes, bytes]]:
    """Write every student's notebooks into ``tmp`` (its release and solutions folders made
    here), yielding their ``(manifest entry, key entry)`` in roster order: in this process, or
    in forked workers for a large class (:func:`_parallel_jobs`)."""
    (tmp / RELEASE).mkdir()
    (tmp / SOLUTIONS).mkdir()
    workers = _parallel_jobs(jobs, len(rows))
    if workers > 1:
        return _students_in_parallel(tmp, plan.title, rows, plan.rerolls, plan.families,
                                     plan.questions, plan.seed, workers, plan.install)
    return _students_here(tmp, plan, rows)


def _students_here(tmp: Path, plan: _Plan, rows: Sequence[Mapping[str, str]]
                   ) -> Iterator[tuple[bytes, bytes]]:
    """:func:`_batch_files` of each batch of rows in this process (the schema checked for the
    first student)."""
    _FORKED.update(families=plan.families, questions=plan.questions, seed=plan.seed,
                   install=plan.install)
    try:
        for task in _batch_tasks(tmp, plan.title, rows, plan.rerolls):
            yield from _batch_files(task)
    finally:
        _FORKED.clear()


def _record_students(rows: Sequence[Mapping[str, str]],
                     entries: Iterable[tuple[bytes, bytes]],
                     manifest: dict, key: dict, progress: Progress | None) -> None:
    """Put each student's entries into the manifest and the key, reporting progress."""
    for done, (row, (entry, answers)) in enumerate(zip(rows, entries, strict=True), start=1):
        manifest["students"][row["id"]] = entry
        key["students"][row["id"]] = answers
        if progress:
            progress(done, len(rows))


def _questions_record(questions: Sequence[Question]) -> list[dict] | None:
    """The manifest's record of the questions when a spec shaped them (a pool, or settings),
    so that a reroll draws with the same; None for plain ``--problems`` questions."""
    if all(len(q.pool) == 1 and q.settings is None for q in questions):
        return None
    return [q.record() for q in questions]


def _outside_families(families: Mapping[str, Family], questions: Sequence[Question],
                      out: Path) -> dict[str, dict]:
    """The manifest's record of the families from outside the package that the questions
    use: a family from a file, that file (relative to ``out``, so that a reroll finds it where
    the assignment was generated); one from an installed package, its entry point; and the
    SHA-256 of its file."""
    used = dict.fromkeys(n for q in questions for n in q.pool)
    record = {}
    for name in used:
        family = families[name]
        if family.origin == "built-in" or family.path is None:
            continue
        path = Path(family.path)
        where = ({"origin": family.origin} if family.origin.startswith("entry point") else
                 {"file": os.path.relpath(path.resolve(), out.resolve())})
        record[name] = {**where, "sha256": hashlib.sha256(path.read_bytes()).hexdigest()}
    return record


def recorded_families(manifest: Mapping, out: Path,
                      families: Mapping[str, Family]) -> dict[str, Family]:
    """``families`` with those from outside the package that ``manifest`` records, loaded from
    their files (relative to ``out``), for a reroll. GenerateError if one cannot be loaded."""
    from problems.family_files import load_family_file

    found = dict(families)
    for name, where in manifest.get("families", {}).items():
        if name in found:
            continue
        if "file" not in where:
            raise GenerateError(f"--reroll: family {name!r} ({where.get('origin')}) is not "
                                "installed here")
        path = Path(out) / where["file"]
        try:
            found[name] = load_family_file(path.parent if path.name == "__init__.py" else path)
        except FamilyError as e:
            raise GenerateError(f"--reroll: family {name!r} of {out / ASSIGNMENT}: {e}") from None
    return found


def recorded_questions(manifest: Mapping, out: Path, families: Mapping[str, Family]
                       ) -> tuple[dict[str, Family], tuple[Question, ...]]:
    """The families (``families`` with those from outside the package the manifest records)
    and the questions an assignment was generated with — its spec's pools and settings, or its
    problems — to generate more of it alike (a reroll, a hosted package's variants).
    GenerateError when one of its families is not to be had here."""
    families = recorded_families(manifest, out, families)
    if "questions" in manifest:
        questions = tuple(Question.from_record(q) for q in manifest["questions"])
        missing = [n for q in questions for n in q.pool if n not in families]
        if missing:
            raise GenerateError(f"--reroll: unknown problem {', '.join(map(repr, missing))}")
    else:
        questions = tuple(Question.of(n) for n in resolve_problems(manifest["problems"],
                                                                     families))
    return families, questions


def recorded_variants(manifest: Mapping, families: Mapping[str, Family],
                      student_id: str) -> tuple[Variant, ...]:
    """A student's variants recomputed from what ``assignment.json`` recorded — each question's
    family and drawn parameters, and a spec's settings — without drawing anything: the key
    again, from the current families (``key_entry`` of them is the student's key entry while
    the families and the solver compute what they did).

    Raises
    ------
    GenerateError
        A question of a family not in ``families``, or without recorded parameters (an
        assignment generated before parameters were recorded).
    """
    recorded = manifest.get("questions")
    variants = []
    for k, question in enumerate(manifest["students"][student_id]["questions"], start=1):
        name = question["family"]
        if name == WRITTEN_QUESTION and recorded is not None:  # a spec's written question
            asked = Question.from_record(recorded[k - 1])
            variants.append(written_variant(asked.written, asked.title))
            continue
        if name not in families or "parameters" not in question:
            raise GenerateError(f"{student_id}, question {k}: no family {name!r} or no "
                                "recorded parameters to recompute it from")
        family, params = families[name], question["parameters"]
        settings = None if recorded is None else Question.from_record(recorded[k - 1]).settings
        answers = family.asked(params, settings)
        if settings is not None:
            answers = settings.adjust_answers(answers)
        variants.append(family.variant(params, answers))
    return tuple(variants)


def reroll_students(
    out: Path,
    student_ids: Sequence[str],
    families: Mapping[str, Family],
    *,
    progress: Progress | None = None,
) -> Summary:
    """Give each of ``student_ids`` a fresh variant in the existing assignment ``out``, drawn
    with the assignment's own questions (and spec settings, and families from outside the
    package, loaded again from the files the manifest records).

    Everything else in ``out`` is kept byte for byte (module docstring, "Rerolls").
    """
    out = Path(out)
    if not (out / ASSIGNMENT).is_file() or not (out / KEY).is_file():
        raise GenerateError(f"--reroll: {out} is not a generated assignment (no {ASSIGNMENT} "
                            f"and {KEY})")
    manifest, key = _read_json(out / ASSIGNMENT), _read_json(out / KEY)
    rows = {row["id"]: row for row in manifest["roster"]["rows"]}
    unknown = [sid for sid in student_ids if sid not in rows]
    if unknown:
        raise GenerateError(f"--reroll: not in the assignment's roster: {', '.join(unknown)}")
    families, questions = recorded_questions(manifest, out, families)
    problems = tuple(q.label for q in questions)
    seed, title = manifest["seed"], manifest["title"]
    ids = tuple(dict.fromkeys(student_ids))  # once each, in the order given
    with _Staging(out) as tmp:
        shutil.copytree(out, tmp, dirs_exist_ok=True)
        for done, sid in enumerate(ids, start=1):
            reroll = manifest["students"][sid]["reroll"] + 1
            variants = student_variants(families, questions, seed, sid, reroll)
            _write_student(tmp, title, rows[sid], variants, families=families,
                           install=manifest.get("student_install"))
            manifest["students"][sid] = manifest_entry(variants, reroll)
            key["students"][sid] = key_entry(variants)
            if progress:
                progress(done, len(ids))
        _write_json(tmp, manifest, key)
    notes = tuple(f"{sid}: reroll {manifest['students'][sid]['reroll']}"
                  + (GRADED_BEFORE if (out / "graded" / "results" / f"{sid}.json").is_file()
                     else "") for sid in ids)
    return Summary(out, seed, problems, ids, notes)


GRADED_BEFORE = ("; graded already: their record holds the answers of their old variant's "
                 "notebook (a rescore compares them with the new key, and names them), and "
                 "'eulertop grade' grades the notebook they hand in for the new one")
"""What :func:`reroll_students` says of a student with a record in ``HW/graded`` (the
grader's default output folder; a class graded elsewhere is not looked for)."""
