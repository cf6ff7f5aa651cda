"""An assignment spec: ``eulertop generate --spec assignment.toml --out HW``.

::

    title = "PHY 711 HW 9"
    seed = 7
    roster = "roster.csv"              # paths relative to this file
    families = ["my_problems"]         # folders of extra families

    [[questions]]
    family = "turning_points"
    points = 6                         # the question's total, spread by the answers' weights

    [[questions]]
    family = "physical_pendulum"
    [questions.answers.T]
    points = 2
    rtol = 5e-3
    [questions.parameters]
    L = 0.75                           # fixed for everyone
    m = [0.2, 0.5]                     # drawn in this range instead of the family's

    [[questions]]
    pool = ["sleeping_top", "steady_precession"]   # each student gets one, from the seed
    points = 4

    [[questions]]
    family = "turning_points"
    written = true                     # the family's written parts too (or ["veff_minimum"])

    [[questions]]                      # a question that is only a written part
    written = "Show that the intermediate axis is unstable."   # the prompt (Markdown)
    name = "intermediate_axis"         # the notebook variable is q5_intermediate_axis
    title = "The tennis-racket theorem"                        # optional
    points = 3                         # optional: the rubric's sum, which it must equal
    rubric = [
      { item = "Euler's equations linearised about the axis", points = 1 },
      { item = "ω₁ satisfies ω̈₁ = −Ω₁Ω₂ ω₁", points = 1 },
      { item = "Ω₁Ω₂ < 0 for the intermediate axis: exponential growth", points = 1 },
    ]

    [student]
    install = "https://example.edu/phy711/eulertop_check-0.1.0-py3-none-any.whl"
                                       # what the notebooks say to %pip install for the check
                                       # (default: eulertop-check)

Every key is optional but ``questions``. A parameter is set to a number (fixed), a range
``[low, high]`` or ``{low = …, high = …}`` (drawn uniformly, rounded to its figures), a label or
a list of labels (a choice parameter: the draws are repeated until one has an allowed label).
A vector parameter is fixed as a list of its numbers (a list of two numbers is a range). Answer
settings are ``points``, ``rtol`` and ``atol``; answer points set this way are kept, and the
question's ``points`` is spread over the other answers in proportion to their own. A written
part (:mod:`problems.written`) is an answer too: its points may be set, and its rubric's items
keep their shares of them; it has no tolerance. A rubric has 1 to 9 items.

:func:`read_spec` reads the file (TOML syntax, known keys, types);
:func:`check_spec` checks it against the families: known families, parameters each family of
the question declares and lets a spec set, values and ranges it accepts, answers it asks for,
and at least one well-posed draw with the settings (:data:`PROBE_ATTEMPTS` tries). Every
problem is a :class:`SpecError` whose one line names the file, the line and the key
(``assignment.toml:14: questions[2].parameters.m: …``).
"""

from __future__ import annotations

import math
import numbers
import re
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from problems.deadlines import LatePolicy, PolicyError, read_policy
from problems.family import Family
from problems.settings import AnswerSetting, ParameterSetting, QuestionSettings
from problems.written import WRITTEN_QUESTION, Written

PROBE_ATTEMPTS = 400
"""Draws :func:`check_spec` tries per family of a question before it calls the settings
ill-posed (and the most it keeps to learn the answers' names from)."""

_TOP_KEYS = ("title", "seed", "roster", "families", "follow_through", "late", "student",
             "questions")
_STUDENT_KEYS = ("install",)
_QUESTION_KEYS = ("family", "pool", "points", "answers", "parameters", "written")
_WRITTEN_KEYS = ("written", "name", "title", "points", "rubric")
"""The keys of a question that is only a written part (``written`` its prompt)."""
_ANSWER_KEYS = ("points", "rtol", "atol")


class SpecError(ValueError):
    """A bad assignment spec; the one-line message names the file, line and key."""


@dataclass(frozen=True)
class QuestionSpec:
    """One ``[[questions]]`` entry: the family (a pool of one) or pool, and its settings; or
    a question that is only a written part (``written``, no pool) and its ``title``."""

    pool: tuple[str, ...]
    settings: QuestionSettings
    written: Written | None = None
    title: str | None = None

    @property
    def label(self) -> str:
        """The manifest's name for it: the family, the pool's families joined by ``|``, or
        ``written:<name>``."""
        if self.written is not None:
            return f"{WRITTEN_QUESTION}:{self.written.name}"
        return "|".join(self.pool)


@dataclass(frozen=True)
class Spec:
    """A spec file as read (paths resolved against the file's folder)."""

    path: Path
    text: str
    title: str | None
    seed: int | None
    roster: Path | None
    families: tuple[Path, ...]
    questions: tuple[QuestionSpec, ...]
    follow_through: float | None = None  # fraction of points follow-through earns (issue 26)
    late: LatePolicy | None = None  # the deadline and late policy, [late] (issue 32)
    install: str | None = None  # [student] install: what the notebooks say to %pip install

    def error(self, key: Sequence[str | int], problem: str) -> SpecError:
        """A :class:`SpecError` for ``key`` (a path into the TOML document)."""
        return SpecError(f"{self.path}:{key_line(self.text, key)}: {key_name(key)}: {problem}")


def key_name(key: Sequence[str | int]) -> str:
    """``("questions", 1, "parameters", "m")`` → ``questions[2].parameters.m`` (1-based)."""
    text = ""
    for part in key:
        text += f"[{part + 1}]" if isinstance(part, int) else (f".{part}" if text else part)
    return text


_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_BARE = r"""(?:[A-Za-z0-9_-]+|"[^"]*"|'[^']*')"""
_KEY = re.compile(rf"^\s*({_BARE}(?:\s*\.\s*{_BARE})*)\s*=")


def _parts(dotted: str) -> list[str]:
    return [p.strip().strip("\"'") for p in re.findall(r"""(?:"[^"]*"|'[^']*'|[^.]+)""", dotted)]


def key_line(text: str, key: Sequence[str | int]) -> int:
    """The line (1-based) where ``key`` is written in the TOML ``text``: its own line, else the
    line of the nearest enclosing table or key that is written (an inline table, a default);
    1 if none is."""
    counts: dict[tuple, int] = {}
    table: tuple = ()
    found: dict[tuple, int] = {}
    depth = 0
    for number, line in enumerate(text.splitlines(), start=1):
        if depth == 0:
            header = _HEADER.match(line)
            if header:
                parts = tuple(_parts(header.group(2)))
                if header.group(1) == "[[":
                    counts[parts] = counts.get(parts, -1) + 1
                table = _with_indices(parts, counts)
                found.setdefault(table, number)
                continue
            match = _KEY.match(line)
            if match:
                full = table + tuple(_parts(match.group(1)))
                for i in range(len(table) + 1, len(full) + 1):
                    found.setdefault(full[:i], number)
        depth += _bracket_change(line)
    for n in range(len(key), 0, -1):
        if tuple(key[:n]) in found:
            return found[tuple(key[:n])]
    return 1


def _with_indices(parts: tuple[str, ...], counts: Mapping[tuple, int]) -> tuple:
    """A table header's path with the index of each array of tables it passes through."""
    path: tuple = ()
    for i, part in enumerate(parts):
        path += (part,)
        if parts[:i + 1] in counts:
            path += (counts[parts[:i + 1]],)
    return path


def _bracket_change(line: str) -> int:
    """Open minus closed brackets and braces outside strings and comments (multi-line
    arrays and tables hold no keys of the document's own)."""
    change, quote = 0, None
    for ch in line:
        if quote:
            quote = None if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch == "#":
            break
        elif ch in "[{":
            change += 1
        elif ch in "]}":
            change -= 1
    return change


def read_spec(path: Path) -> Spec:
    """Read and check the form of the spec at ``path`` (not yet against the families).

    Raises
    ------
    SpecError
        Unreadable, not TOML, an unknown key, a value of the wrong type, points ≤ 0.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SpecError(f"{path}: cannot read the spec: {e}") from None
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        where = re.search(r"\(at line (\d+), column \d+\)", str(e))
        message = re.sub(r"\s*\(at line \d+, column \d+\)", "", str(e))
        line = where.group(1) if where else "1"
        raise SpecError(f"{path}:{line}: not valid TOML: {message}") from None
    draft = Spec(path, text, None, None, None, (), ())
    _known(draft, document, (), _TOP_KEYS)
    title = _typed(draft, document, ("title",), str, "a string")
    seed = _typed(draft, document, ("seed",), int, "a whole number")
    if seed is not None and seed < 0:
        raise draft.error(("seed",), f"must be ≥ 0, got {seed}")
    roster = _typed(draft, document, ("roster",), str, "a path (a string)")
    folders = _typed(draft, document, ("families",), list, "a list of folders")
    for i, folder in enumerate(folders or ()):
        if not isinstance(folder, str):
            raise draft.error(("families", i), f"must be a folder (a string), got {folder!r}")
        if not (path.parent / folder).is_dir():
            raise draft.error(("families", i), f"{path.parent / folder}: no such folder")
    follow = _positive(draft, document, ("follow_through",), zero=True)
    if follow is not None and follow > 1:
        raise draft.error(("follow_through",), f"must be a fraction from 0 to 1, got {follow!r}")
    install = _install(draft, document)
    entries = document.get("questions")
    if not isinstance(entries, list) or not entries:
        raise draft.error(("questions",), "give at least one [[questions]] table")
    questions = tuple(_question(draft, q, i) for i, q in enumerate(entries))
    base = path.parent
    return Spec(path, text, title, seed, None if roster is None else base / roster,
                tuple(base / f for f in folders or ()), questions, follow,
                _late(draft, document), install)


def _late(spec: Spec, document: Mapping) -> LatePolicy | None:
    """The ``[late]`` table as a policy (:mod:`problems.deadlines`), None when absent."""
    if "late" not in document:
        return None
    try:
        return read_policy(document["late"])
    except PolicyError as e:
        key, _, problem = str(e).partition(": ")
        parts = ("late", *key.split(".")) if problem and " " not in key else ("late",)
        raise spec.error(parts, problem if len(parts) > 1 else str(e)) from None


def _install(spec: Spec, document: Mapping) -> str | None:
    """``[student] install``: what each notebook's first cell tells the student to
    ``%pip install`` for the check (a wheel's address, a package name); one line."""
    if "student" not in document:
        return None
    _known(spec, document["student"], ("student",), _STUDENT_KEYS)
    install = _typed(spec, document["student"], ("student", "install"), str, "a string")
    if install is not None and (not install.strip() or len(install.splitlines()) > 1):
        raise spec.error(("student", "install"), f"must be one line naming what to install, "
                         f"got {install!r}")
    return None if install is None else install.strip()


def _known(spec: Spec, table: Any, key: tuple, allowed: Sequence[str]) -> None:
    if not isinstance(table, Mapping):
        raise spec.error(key, f"must be a table, got {table!r}")
    for name in table:
        if name not in allowed:
            raise spec.error((*key, name), f"unknown key; known: {', '.join(allowed)}")


def _typed(spec: Spec, table: Mapping, key: tuple, kind: type, what: str) -> Any:
    value = table.get(key[-1])
    if value is not None and (not isinstance(value, kind) or isinstance(value, bool)):
        raise spec.error(key, f"must be {what}, got {value!r}")
    return value


def _number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool) \
        and math.isfinite(value)


def _positive(spec: Spec, table: Mapping, key: tuple, zero: bool = False) -> float | None:
    value = table.get(key[-1])
    if value is None:
        return None
    if not _number(value) or value < 0 or (value == 0 and not zero):
        raise spec.error(key, f"must be a number {'≥' if zero else '>'} 0, got {value!r}")
    return float(value)


def _question(spec: Spec, entry: Any, i: int) -> QuestionSpec:
    key = ("questions", i)
    if isinstance(entry, Mapping) and isinstance(entry.get("written"), str):
        return _written_question(spec, entry, key)
    _known(spec, entry, key, _QUESTION_KEYS)
    family, pool = entry.get("family"), entry.get("pool")
    if (family is None) == (pool is None):
        raise spec.error(key, "give either family = \"name\" or pool = [\"a\", \"b\", …]")
    if family is not None:
        if not isinstance(family, str):
            raise spec.error((*key, "family"), f"must be a family's name, got {family!r}")
        pool = [family]
    elif not isinstance(pool, list) or not pool or not all(isinstance(n, str) for n in pool):
        raise spec.error((*key, "pool"), f"must be a list of family names, got {pool!r}")
    elif len(set(pool)) != len(pool):
        raise spec.error((*key, "pool"), f"names a family twice: {pool!r}")
    points = _positive(spec, entry, (*key, "points"))
    answers = entry.get("answers", {})
    _known(spec, answers, (*key, "answers"), list(answers) if isinstance(answers, dict) else ())
    settings = {}
    for name, table in answers.items():
        where = (*key, "answers", name)
        _known(spec, table, where, _ANSWER_KEYS)
        rtol = _positive(spec, table, (*where, "rtol"))
        if rtol is not None and rtol >= 1:
            raise spec.error((*where, "rtol"), f"must be below 1 (a fraction), got {rtol!r}")
        settings[name] = AnswerSetting(_positive(spec, table, (*where, "points")), rtol,
                                       _positive(spec, table, (*where, "atol"), zero=True))
    parameters = entry.get("parameters", {})
    _known(spec, parameters, (*key, "parameters"),
           list(parameters) if isinstance(parameters, dict) else ())
    values = {name: _parameter(spec, value, (*key, "parameters", name))
              for name, value in parameters.items()}
    return QuestionSpec(tuple(pool), QuestionSettings(points, settings, values,
                                                      _written_parts(spec, entry, key)))


def _written_parts(spec: Spec, entry: Mapping, key: tuple) -> bool | tuple[str, ...]:
    """A family question's ``written``: true (every written part of its family), a list of
    their names, or absent (none)."""
    chosen = entry.get("written", False)
    if isinstance(chosen, bool):
        return chosen
    if isinstance(chosen, list) and chosen and all(isinstance(n, str) for n in chosen):
        return tuple(chosen)
    raise spec.error((*key, "written"), "must be true, a list of the family's written parts' "
                                        f"names, or a prompt (text) of its own; got {chosen!r}")


def _written_question(spec: Spec, entry: Mapping, key: tuple) -> QuestionSpec:
    """A ``[[questions]]`` entry that is only a written part: ``written`` (its prompt),
    ``name``, ``rubric``, and optionally ``points`` (the rubric's sum) and ``title``."""
    _known(spec, entry, key, _WRITTEN_KEYS)
    name = _typed(spec, entry, (*key, "name"), str, "a name (a string)")
    if name is None or not name.isidentifier():
        raise spec.error((*key, "name"), f"a written question needs a name that can end a "
                                         f"Python variable (q5_<name>), got {name!r}")
    title = _typed(spec, entry, (*key, "title"), str, "a string")
    rubric = entry.get("rubric")
    if not isinstance(rubric, list) or not rubric:
        raise spec.error((*key, "rubric"), "give the rubric: a list of { item = \"…\", "
                                           "points = N }")
    for n, item in enumerate(rubric):
        _known(spec, item, (*key, "rubric", n), ("item", "points"))
    try:
        written = Written(name, entry["written"], _positive(spec, entry, (*key, "points")),
                          [(item.get("item"), item.get("points")) for item in rubric])
    except ValueError as e:
        raise spec.error((*key, "rubric" if "rubric" in str(e) else "written"),
                         str(e).split(": ", 1)[-1]) from None
    return QuestionSpec((), QuestionSettings(), written, title)


def _parameter(spec: Spec, value: Any, key: tuple) -> ParameterSetting:
    """A parameter's setting, by its form (checked against the family by check_spec)."""
    if isinstance(value, Mapping):
        _known(spec, value, key, ("low", "high"))
        low, high = value.get("low"), value.get("high")
        if not (_number(low) and _number(high)):
            raise spec.error(key, "a range needs numbers low and high")
        if low > high:
            raise spec.error(key, f"the range [{low!r}, {high!r}] has low > high")
        return ParameterSetting(None, float(low), float(high))
    if isinstance(value, str):
        return ParameterSetting(value=value)
    if _number(value):
        return ParameterSetting(value=float(value))
    if isinstance(value, list) and value and all(isinstance(v, str) for v in value):
        return ParameterSetting(choices=tuple(value))
    if isinstance(value, list) and len(value) == 2 and all(_number(v) for v in value):
        if value[0] > value[1]:
            raise spec.error(key, f"the range {value!r} has low > high")
        return ParameterSetting(None, float(value[0]), float(value[1]))
    if isinstance(value, list) and value and all(_number(v) for v in value):
        return ParameterSetting(value=[float(v) for v in value])
    raise spec.error(key, f"must be a number, [low, high], a label or a list of labels; got "
                          f"{value!r}")


def check_spec(spec: Spec, families: Mapping[str, Family]) -> None:
    """Check ``spec`` against ``families`` (module docstring); SpecError at the first
    problem."""
    for i, question in enumerate(spec.questions):
        key = ("questions", i)
        if question.written is not None:
            continue  # nothing drawn: read_spec checked it whole
        where = (*key, "family" if len(question.pool) == 1 else "pool")
        unknown = [n for n in question.pool if n not in families]
        if unknown:
            raise spec.error(where, f"unknown family {', '.join(map(repr, unknown))}; known: "
                                    f"{', '.join(families)}")
        settings = question.settings
        for name, setting in settings.parameters.items():
            for family in (families[n] for n in question.pool):
                _check_parameter(spec, (*key, "parameters", name), family, name, setting)
        names: set[str] = set()
        kinds: dict[str, str] = {}
        for family in (families[n] for n in question.pool):
            probed = replace(settings, written=True) if settings.written else settings
            seen = _probe(spec, (*key, "parameters") if settings.parameters else where,
                          family, probed)  # every written part it offers, to name them
            _check_written(spec, (*key, "written"), family, settings.written, seen)
            seen = [a for a in seen if a.kind != "written" or settings.written is True
                    or a.name in settings.written]
            names |= {a.name for a in seen}
            kinds |= {a.name: a.kind for a in seen}
        _check_answers(spec, key, settings, names, kinds)


def _check_written(spec: Spec, key: tuple, family: Family, chosen: bool | tuple[str, ...],
                   seen: Sequence[Any]) -> None:
    """The written parts a question asks of ``family`` are ones it offers (``seen``: the
    answers of its probe draws, every written part it offers among them)."""
    if not chosen:
        return
    offered = {a.name for a in seen if a.kind == "written"}
    wanted = set(offered) if chosen is True else set(chosen)
    if not offered or wanted - offered:
        has = ", ".join(sorted(offered)) or "none"
        missing = ", ".join(sorted(wanted - offered)) or "a written part"
        raise spec.error(key, f"{family.name} has no written part {missing}; its written "
                              f"parts: {has}")


def _check_parameter(spec: Spec, key: tuple, family: Family, name: str,
                     setting: ParameterSetting) -> None:
    declared = family.parameters
    if name not in declared:
        raise spec.error(key, f"{family.name} has no parameter {name!r}; it has "
                              f"{', '.join(declared)}")
    p = declared[name]
    settable = [n for n, q in declared.items() if q.settable]
    if not p.settable:
        raise spec.error(key, f"{family.name} derives {name!r} from its other parameters, so a "
                              f"spec cannot set it; it can set {', '.join(settable) or 'none'}")
    if p.is_choice:
        labels = (setting.value,) if setting.value is not None else setting.choices
        bad = [v for v in labels if v not in p.choices]
        if bad or (setting.value is None and not setting.choices):
            raise spec.error(key, f"{family.name}.{name} is one of "
                                  f"{', '.join(map(repr, p.choices))}; got {labels or setting}")
        return
    if setting.value is not None:
        problem = p.problem(setting.value)
        if problem:
            raise spec.error(key, f"{family.name}.{name}: {problem}")
        return
    if setting.choices:
        raise spec.error(key, f"{family.name}.{name} is a number, not a label")
    if setting.low < p.low or setting.high > p.high:
        raise spec.error(key, f"the range [{setting.low:g}, {setting.high:g}] is outside what "
                              f"{family.name} accepts for {name}, [{p.low:g}, {p.high:g}]")


def _probe(spec: Spec, key: tuple, family: Family, settings: QuestionSettings) -> list:
    """Answers of up to a few well-posed draws with ``settings``; SpecError if there is none
    in :data:`PROBE_ATTEMPTS` tries."""
    rng = np.random.default_rng(0)
    found = []
    for _ in range(PROBE_ATTEMPTS):
        try:
            drawn = family.accepted(rng, settings)
        except Exception as e:
            raise spec.error(key, f"{family.name} failed with these settings: "
                                  f"{type(e).__name__}: {e}") from None
        if drawn is not None:
            found.extend(drawn[1])
            if len(found) >= 8 * len(drawn[1]):
                break
    if not found:
        raise spec.error(key, f"no well-posed draw of {family.name} in {PROBE_ATTEMPTS} tries "
                              "with these parameters; widen the ranges or fix other values")
    return found


def _check_answers(spec: Spec, key: tuple, settings: QuestionSettings, names: set[str],
                   kinds: Mapping[str, str]) -> None:
    for name, setting in settings.answers.items():
        where = (*key, "answers", name)
        if name not in names:
            raise spec.error(where, f"no such answer; the question asks for "
                                    f"{', '.join(sorted(names))}")
        if kinds[name] in ("boolean", "choice", "written") \
                and (setting.rtol, setting.atol) != (None, None):
            raise spec.error(where, f"a {kinds[name]} answer has no tolerance")
    fixed = sum(s.points for s in settings.answers.values() if s.points is not None)
    if settings.points is not None:
        free = names - {n for n, s in settings.answers.items() if s.points is not None}
        if fixed > settings.points or (not free and fixed != settings.points):
            raise spec.error((*key, "points"), f"the answers' own points add up to {fixed:g}, "
                                               f"which does not fit the total {settings.points:g}")
