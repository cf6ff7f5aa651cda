"""The problem-family contract, and one family loaded and checked against it.

A family is a Python module (one file, or a package) that defines::

    NAME = "physical_pendulum"          # unique: the name in --problems and specs
    TITLE = "..."                       # the question's title
    SUMMARY = "..."                     # one line for `eulertop problems`
    PARAMETERS = {"L": Parameter(unit="m", low=0.2, high=2.0, figures=3), ...}
    def answers(params) -> tuple[Answer, ...]   # pure: from the shown params alone
    def statement(params) -> str                # Markdown + LaTeX, as the student reads it

and may define ``draw(rng) -> dict | None`` (default :func:`draw_parameters`: each parameter
drawn in its range and rounded to its figures), ``heading(params) -> str`` (a title for these
parameters; default ``TITLE``), ``written(params)`` (the written parts it offers:
:class:`problems.written.Written` records, which an assignment spec asks for by
``written = true`` or their names), ``RESULTS`` (R-ids of ``docs/physics/index.md``),
``CONVENTIONS`` (topics of :mod:`problems.conventions` its statement relies on), ``prepare()``
(one-time work, done before the generator forks its workers) and ``MAX_ATTEMPTS`` (draws before
giving up).

An answer the statement asks to compute from earlier answers of its question is declared with
:func:`follows_from`; then ``follow(name, params, earlier)`` recomputes it from a student's own
earlier values (follow-through credit), and ``degenerate(name, params, earlier) -> str | None``
may say why such values are no ground for that credit — a value that leaves nothing to work out
(the defaults every family gets, :mod:`problems.genuine`, apply besides).

The batch form (optional): ``draw_many(rngs) -> list`` and ``answers_many(params_list) -> list``
do for many students at once what ``draw`` and ``answers`` do for one — so that a family can
call the solver once for a whole class instead of once per student. Element ``i`` of the result
must be exactly what ``draw(rngs[i])`` (each student's draw from that student's own generator,
which it uses as ``draw`` would) or ``answers(params_list[i])`` gives; a rejected element is
None (``draw_many``) or an :class:`IllPosed` instance (``answers_many``), not raised.
:meth:`Family.generate_many` draws a class through them, one student at a time for a family
without them: the variants, and so the files, are the same either way.

Drawing is kept apart from answering, so that a key can be recomputed from the parameters an
assignment recorded: :meth:`Family.variant` is ``answers(params)`` and ``statement(params)``
and nothing else. A draw that is ill-posed (turning points that nearly coincide, a known mistake
that cannot be told from the key) is rejected by returning None from ``draw`` or by raising
:class:`IllPosed` from ``draw`` or ``answers``; :meth:`Family.generate` then draws again from
the same generator.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from problems.answers import Answer, distinguishable_answers
from problems.rounding import round_sig
from problems.variant import Variant, plain_number_tree

if TYPE_CHECKING:
    from problems.settings import QuestionSettings

MAX_ATTEMPTS = 1000
"""Draws :meth:`Family.generate` makes before it gives up, unless the family says otherwise."""


class IllPosed(Exception):
    """Raised by a family's ``draw`` or ``answers``: these parameters make no good question
    (the generator draws again)."""


class FamilyError(ValueError):
    """A family that does not keep the contract; the message names its file."""


def follows_from(answer: Answer | None, *names: str) -> Answer | None:
    """``answer`` declared as computed from the earlier answers ``names`` of its question
    (``Answer.depends_on``; the family's ``follow`` recomputes it from them), None left None
    (a rejected draw's answer)."""
    return None if answer is None else answer.following(*names)


def reject_unless(condition: bool, reason: str) -> None:
    """Raise :class:`IllPosed` with ``reason`` unless ``condition`` holds."""
    if not condition:
        raise IllPosed(reason)


def distinguishable(build: Callable[[], tuple[Answer, ...]], margin: float) -> tuple[Answer, ...]:
    """``build()``'s answers, every known mistake ``margin`` tolerances from the key and from
    the others (:func:`problems.answers.distinguishable_answers`), else :class:`IllPosed`."""
    answers = distinguishable_answers(build, margin)
    if answers is None:
        raise IllPosed(f"a known mistake within {margin:g} tolerances of the key or another")
    return answers


def drawn_scene(scenes: Mapping[str, Any], rng: np.random.Generator) -> str:
    """The name of one of ``scenes`` (in their order) drawn at random: one integer from
    ``rng``, a family's first draw of a variant."""
    return list(scenes)[int(rng.integers(len(scenes)))]


def batch_of_one(many: Callable[[list], list], params: Mapping[str, Any]) -> Any:
    """What the batch form ``many`` (an :class:`IllPosed` element where it rejects) gives for
    the one parameter set ``params``; that IllPosed raised."""
    found = many([params])[0]
    if isinstance(found, IllPosed):
        raise found
    return found


def redrawn_until_well_posed(
    draw_once: Callable[[np.random.Generator], dict | None],
    answers: Callable[[Mapping[str, Any]], tuple[Answer, ...]],
    rng: np.random.Generator, tries: int,
) -> dict | None:
    """``draw_once(rng)`` repeated until ``answers`` accepts its parameters (at most
    ``tries``; None if it never does): the ``draw`` of a family that picks its scene once per
    variant and redraws within that scene."""
    for _ in range(tries):
        params = draw_once(rng)
        if params is None:
            continue
        try:
            answers(params)
        except IllPosed:
            continue
        return params
    return None


def redrawn_many_until_well_posed(
    draws_once: Sequence[Callable[[np.random.Generator], dict | None]],
    posed_many: Callable[[list[dict]], list[Any]],
    rngs: Sequence[np.random.Generator], tries: int,
) -> list[dict | None]:
    """:func:`redrawn_until_well_posed` of each student, ``draws_once[i]`` from ``rngs[i]``:
    round by round, one try of every student still without an accepted one, all of them
    tested by one call of ``posed_many`` (an :class:`IllPosed` element: rejected) — a batch
    ``draw`` (:meth:`Family.draw_many`). Each generator is used as the student's alone
    would be: the same tries, in the same order."""
    found: list[dict | None] = [None] * len(rngs)
    pending = list(range(len(rngs)))
    for _ in range(tries):
        tried = [(i, draws_once[i](rngs[i])) for i in pending]
        drawn = [(i, params) for i, params in tried if params is not None]
        verdicts = posed_many([params for _, params in drawn]) if drawn else []
        for (i, params), verdict in zip(drawn, verdicts, strict=True):
            if not isinstance(verdict, IllPosed):
                found[i] = params
        pending = [i for i in pending if found[i] is None]
        if not pending:
            break
    return found


def stacked_dots(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Dot products of stacked vectors ``u``, ``v`` (..., n), bit for bit ``numpy.dot`` of each
    pair: the same BLAS dot, one per pair (a sum in another order, as ``einsum``'s, changes the
    last bits), for a batch form to give exactly what one student alone gets."""
    return (u[..., None, :] @ v[..., :, None])[..., 0, 0]


def stacked_norms(v: np.ndarray) -> np.ndarray:
    """Euclidean norms of stacked vectors (..., n), bit for bit ``numpy.linalg.norm`` of each
    (:func:`stacked_dots`)."""
    return np.sqrt(stacked_dots(v, v))


def stacked_apart(values: np.ndarray, tol: np.ndarray) -> np.ndarray:
    """Whether, stack by stack, the vectors ``values[..., k, :]`` (a key, then its known
    mistakes) lie further than ``tol`` (...) from one another, every pair by the norm of
    their difference (:func:`stacked_norms`): a family's test that each can be told apart."""
    first, second = np.triu_indices(values.shape[-2], 1)
    gaps = stacked_norms(values[..., first, :] - values[..., second, :])
    return ~np.any(gaps <= tol[..., None], axis=-1)


def stacked_distinguishable(values: np.ndarray, rtol: float, atol: float = 0.0) -> np.ndarray:
    """Whether, row by row, the finite values ``values`` (n, k) of a scalar answer — its key,
    then its known mistakes in order — pass :func:`problems.answers.mistakes_distinguishable`
    with the tolerances ``rtol`` and ``atol`` already widened by its margin: each mistake
    further than ``atol + rtol·|v|`` from the key and from every mistake ``v`` before it (the
    same float operations, so the same verdict, without building the answer)."""
    tolerance = atol + rtol * np.abs(values)  # each value's, as the reference of later ones
    later, earlier = np.tril_indices(values.shape[-1], -1)
    close = np.abs(values[:, later] - values[:, earlier]) <= tolerance[:, earlier]
    return ~np.any(close, axis=-1) & np.all(tolerance[:, 1:] >= 0.0, axis=-1)


def remembered(work: Callable[[Mapping[str, Any]], Any]) -> Callable[[Mapping[str, Any]], Any]:
    """``work(params)`` remembering its last result, given again for equal parameters: the
    work a family's ``draw`` tests each try with (:func:`redrawn_until_well_posed`), which its
    ``answers`` repeats on the accepted try, done once. ``work`` must be pure and its result
    left unchanged by its callers; what it raises (:class:`IllPosed`) is not remembered."""
    last: list = [None, None]  # (parameters, result)

    def once(params: Mapping[str, Any]) -> Any:
        key = tuple((name, _exact(value)) for name, value in params.items())
        if last[0] != key:
            last[:] = [key, work(params)]
        return last[1]

    once.__doc__, once.__name__ = work.__doc__, work.__name__
    return once


def _exact(value: Any) -> Any:
    """``value`` as compared for :func:`remembered`: equal only to an equal value of the same
    type (``1`` is not ``1.0``, nor ``0.0`` ``-0.0``; lists element by element)."""
    if type(value) is float:
        return value if value else (value, math.copysign(1.0, value))
    if type(value) is list:
        return (list, tuple(_exact(v) for v in value))
    return (type(value), value)


@dataclass(frozen=True)
class Parameter:
    """One parameter of a family: a number (or an array of numbers) or a choice among labels.

    Attributes
    ----------
    unit : str
        SI unit shown with it (``"m"``, ``"kg m^2"``, ``"rad/s"``); ``""`` if dimensionless.
    low, high : float or None
        The range the family accepts, and the default draw's range. A parameter without one is
        derived by the family's ``draw`` (from other parameters, or from quantities the student
        is not shown) and cannot be set by an assignment spec.
    figures : int or None
        Significant figures it is shown with (and rounded to); None: not rounded (a derived
        value the statement does not print, such as ``3h/4``).
    shape : tuple of int or None
        ``()`` for a number, ``(3,)`` for a vector, ``(3, 3)`` for a matrix; None for any of
        them (a parameter that is a vector in one scene and a number in another; drawn as a
        number).
    choices : tuple of str
        A choice parameter (a scene, a body): one of these labels. A spec may fix it or narrow
        it to some of them (the draw is then repeated until it gives one of those).
    cell : bool
        Whether it is a variable of the student's parameter cell (``q{k}_{name}``). Choices
        never are; a number with ``cell=False`` is only written into the statement.
    description : str
        What it is, in a few words (for ``eulertop problems preview`` and error messages).
    """

    unit: str = ""
    low: float | None = None
    high: float | None = None
    figures: int | None = 3
    shape: tuple[int, ...] | None = ()
    choices: tuple[str, ...] = ()
    cell: bool = True
    description: str = ""

    def __post_init__(self) -> None:
        if (self.low is None) != (self.high is None):
            raise ValueError("give both low and high, or neither")
        if self.low is not None and not (_finite(self.low) and _finite(self.high)
                                         and self.low <= self.high):
            raise ValueError(f"need finite low <= high, got {self.low!r}, {self.high!r}")
        if self.figures is not None and (not isinstance(self.figures, int)
                                         or isinstance(self.figures, bool) or self.figures < 1):
            raise ValueError(f"figures must be a whole number >= 1 or None, got {self.figures!r}")
        if self.choices and (self.low is not None or self.shape):
            raise ValueError("a choice parameter has no range and no shape")
        if self.choices and not all(isinstance(c, str) and c for c in self.choices):
            raise ValueError(f"choices must be non-empty strings, got {self.choices!r}")
        if self.shape is not None:
            object.__setattr__(self, "shape", tuple(self.shape))
        object.__setattr__(self, "choices", tuple(self.choices))

    @property
    def is_choice(self) -> bool:
        """A choice among labels rather than a number."""
        return bool(self.choices)

    @property
    def settable(self) -> bool:
        """Whether an assignment spec may fix it or give it another range."""
        return self.is_choice or self.low is not None

    @property
    def in_cell(self) -> bool:
        """Whether it is a variable of the student's parameter cell."""
        return self.cell and not self.is_choice

    def draw(self, rng: np.random.Generator, low: float | None = None,
             high: float | None = None) -> float | list | str:
        """A value: a label drawn uniformly, or numbers uniform in ``[low, high]`` (default:
        the parameter's range), rounded to its figures."""
        if self.is_choice:
            return self.choices[int(rng.integers(len(self.choices)))]
        low = self.low if low is None else low
        high = self.high if high is None else high
        if low is None:
            raise ValueError("no range to draw from")
        value = rng.uniform(low, high, size=self.shape) if self.shape else rng.uniform(low, high)
        if self.figures is not None:
            value = round_sig(value, self.figures)
        return np.asarray(value).tolist() if self.shape else float(value)

    def problem(self, value: Any) -> str | None:
        """What is wrong with ``value`` for this parameter (type, shape, range, figures), or
        None."""
        if self.is_choice:
            if value not in self.choices:
                return f"must be one of {', '.join(map(repr, self.choices))}, got {value!r}"
            return None
        try:
            numbers_ = np.asarray(plain_number_tree(value, "value"), dtype=float)
        except ValueError as e:
            return str(e).removeprefix("value: ")
        if self.shape is not None and numbers_.shape != self.shape:
            return f"must have shape {self.shape}, got {numbers_.shape}"
        for x in numbers_.ravel().tolist():
            if self.low is not None and not self.low <= x <= self.high:
                return f"{x!r} is outside [{self.low!r}, {self.high!r}]"
            if self.figures is not None and round_sig(x, self.figures) != x:
                return f"{x!r} has more than {self.figures} significant figures"
        return None


def _finite(x: Any) -> bool:
    return isinstance(x, numbers.Real) and not isinstance(x, bool) and math.isfinite(x)


def draw_parameters(rng: np.random.Generator,
                    parameters: Mapping[str, Parameter]) -> dict[str, Any]:
    """The default ``draw``: every parameter in its range (labels uniformly), in order.

    Raises
    ------
    ValueError
        A parameter has neither a range nor choices (the family must define ``draw``).
    """
    return {name: p.draw(rng) for name, p in parameters.items()}


_REQUIRED = ("NAME", "TITLE", "SUMMARY", "PARAMETERS", "answers", "statement")


@dataclass(frozen=True, eq=False)
class Family:
    """A family module, checked against the contract (module docstring), and what it does.

    Attributes
    ----------
    module : module
        The family's own module (or any object with its attributes).
    origin : str
        Where it comes from, for ``eulertop problems``: ``"built-in"``, its file (as the
        folder or path was given: ``my_problems/pendulum.py``), or ``"entry point NAME
        (DIST)"``.
    path : Path or None
        Its source file (a package's ``__init__.py``), named in error messages.
    """

    module: Any
    origin: str = "built-in"
    path: Path | None = None

    def __post_init__(self) -> None:
        check_contract(self.module, self.where)

    @property
    def where(self) -> str:
        """How messages name the family: its file, else its module."""
        return str(self.path) if self.path else getattr(self.module, "__name__", "family")

    @property
    def name(self) -> str:
        return self.module.NAME

    @property
    def title(self) -> str:
        return self.module.TITLE

    @property
    def summary(self) -> str:
        return self.module.SUMMARY

    @property
    def results(self) -> tuple[str, ...]:
        return tuple(getattr(self.module, "RESULTS", ()))

    @property
    def conventions(self) -> tuple[str, ...]:
        return tuple(getattr(self.module, "CONVENTIONS", ()))

    @property
    def parameters(self) -> dict[str, Parameter]:
        return dict(self.module.PARAMETERS)

    @property
    def max_attempts(self) -> int:
        return int(getattr(self.module, "MAX_ATTEMPTS", MAX_ATTEMPTS))

    def prepare(self) -> None:
        """The family's one-time work (``prepare()``), if it has any."""
        prepare = getattr(self.module, "prepare", None)
        if prepare is not None:
            prepare()

    def draw(self, rng: np.random.Generator) -> dict[str, Any] | None:
        """One draw of parameters (None or :class:`IllPosed`: rejected)."""
        own = getattr(self.module, "draw", None)
        return draw_parameters(rng, self.module.PARAMETERS) if own is None else own(rng)

    def answers(self, params: Mapping[str, Any]) -> tuple[Answer, ...]:
        """The key for ``params`` (:class:`IllPosed` if they make no good question)."""
        return tuple(self.module.answers(dict(params)))

    def written(self, params: Mapping[str, Any]) -> tuple[Answer, ...]:
        """The written parts the family offers for ``params`` (its ``written``; none without
        one), as the key's answers of kind ``written`` (:mod:`problems.written`)."""
        from problems.written import Written

        own = getattr(self.module, "written", None)
        parts = () if own is None else tuple(own(dict(params)))
        if not all(isinstance(w, Written) for w in parts):
            raise TypeError(f"{self.where}: written() must return Written records")
        return tuple(w.answer() for w in parts)

    def asked(self, params: Mapping[str, Any],
              settings: QuestionSettings | None = None) -> tuple[Answer, ...]:
        """The answers a question of this family asks for ``params``: :meth:`answers`, then
        the written parts ``settings`` ask for (its ``written``: all, some by name, or none),
        before the settings change points and tolerances."""
        return self.with_written(params, self.answers(params), settings)

    def with_written(self, params: Mapping[str, Any], answers: tuple[Answer, ...],
                     settings: QuestionSettings | None) -> tuple[Answer, ...]:
        """``answers`` (of ``params``) and the written parts ``settings`` ask for (its
        ``written``: all, some by name, or none) after them."""
        chosen = None if settings is None else settings.written
        if not chosen:
            return answers
        parts = self.written(params)
        return answers + tuple(w for w in parts if chosen is True or w.name in chosen)

    @property
    def batched(self) -> bool:
        """Whether the family has a batch form (``draw_many`` or ``answers_many``)."""
        return any(hasattr(self.module, hook) for hook in ("draw_many", "answers_many"))

    def draw_many(self, rngs: Sequence[np.random.Generator]) -> list[dict[str, Any] | None]:
        """:meth:`draw` of each generator (None: rejected): the family's ``draw_many``, else
        one at a time."""
        own = getattr(self.module, "draw_many", None)
        if own is not None:
            return self._checked_many("draw_many", own(list(rngs)), len(rngs))
        drawn = (unless_ill_posed(self.draw, rng) for rng in rngs)
        return [None if isinstance(params, IllPosed) else params for params in drawn]

    def answers_many(self, many: Sequence[Mapping[str, Any]]
                     ) -> list[tuple[Answer, ...] | IllPosed]:
        """:meth:`answers` of each parameter set (an :class:`IllPosed` where rejected): the
        family's ``answers_many``, else one at a time."""
        own = getattr(self.module, "answers_many", None)
        if own is None or not many:
            return [unless_ill_posed(self.answers, params) for params in many]
        found = self._checked_many("answers_many", own([dict(p) for p in many]), len(many))
        return [r.with_traceback(None) if isinstance(r, IllPosed) else tuple(r) for r in found]

    def _checked_many(self, hook: str, found: Any, n: int) -> list:
        found = list(found)
        if len(found) != n:
            raise TypeError(f"{self.where}: {hook}() must return one element per student "
                            f"({n}), got {len(found)}")
        return found

    def statement(self, params: Mapping[str, Any]) -> str:
        return self.module.statement(dict(params))

    def follow(self, name: str, params: Mapping[str, Any], earlier: Mapping[str, Any]) -> Any:
        """Answer ``name`` recomputed from the parameters and the values ``earlier`` gives the
        answers it depends on (``Answer.depends_on``): the family's ``follow``, what
        follow-through credit compares a student's answer with; LookupError where the family
        has none."""
        own = getattr(self.module, "follow", None)
        if own is None:
            raise LookupError(f"{self.where}: no follow() for answer {name!r}")
        return own(name, dict(params), dict(earlier))

    def degenerate(self, name: str, params: Mapping[str, Any],
                   earlier: Mapping[str, Any]) -> str | None:
        """Why a student's earlier values ``earlier`` make answer ``name`` follow trivially —
        one line, naming answers and parameters as ``{name}`` — or None: the family's own
        ``degenerate`` (None where it has none), checked before the defaults of
        :mod:`problems.genuine`. TypeError naming the family for a reply that is not text."""
        own = getattr(self.module, "degenerate", None)
        reason = None if own is None else own(name, dict(params), dict(earlier))
        if reason is not None and (not isinstance(reason, str) or not reason.strip()):
            raise TypeError(f"{self.where}: degenerate() must return a reason (text) or None, "
                            f"got {reason!r}")
        return reason

    def heading(self, params: Mapping[str, Any]) -> str:
        """The question's title for ``params``: the family's ``heading``, else ``TITLE``."""
        own = getattr(self.module, "heading", None)
        return self.title if own is None else own(dict(params))

    def variant(self, params: Mapping[str, Any],
                answers: tuple[Answer, ...] | None = None) -> Variant:
        """The variant of ``params`` (recorded or just drawn): their answers (unless given),
        statement and title; the parameter cell holds the numbers with ``cell=True``."""
        return self._variant(self.recorded(params), answers)

    def _variant(self, params: dict[str, Any], answers: tuple[Answer, ...] | None) -> Variant:
        """:meth:`variant` of parameters already as :meth:`recorded` gives them (a draw's)."""
        if answers is None:
            answers = self.answers(params)
        if not all(isinstance(a, Answer) for a in answers):
            raise TypeError(f"{self.where}: answers() must return Answer records")
        heading, statement = self.heading(params), self.statement(params)
        for what, text in (("heading()", heading), ("statement()", statement)):
            if not isinstance(text, str) or not text.strip():
                raise TypeError(f"{self.where}: {what} must return text, got {text!r}")
        declared = self.module.PARAMETERS
        cell = {k: v for k, v in params.items() if declared[k].in_cell}
        units = {k: declared[k].unit for k in cell if declared[k].unit}
        return Variant(self.name, heading, cell, units, statement, answers, parameters=params)

    def recorded(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """``params`` as plain JSON (floats, lists of floats, labels), every name declared in
        ``PARAMETERS``; ``ValueError`` naming the family otherwise."""
        if not isinstance(params, Mapping):
            raise ValueError(f"{self.where}: draw() must return a dict, got {params!r}")
        declared = self.module.PARAMETERS
        unknown = [k for k in params if k not in declared]
        if unknown:
            raise ValueError(f"{self.where}: parameters not declared in PARAMETERS: {unknown}")
        plain = {}
        for name, value in params.items():
            if type(value) is float and math.isfinite(value) and not declared[name].choices:
                plain[name] = value  # the common case, first
            elif declared[name].is_choice:
                if value not in declared[name].choices:
                    raise ValueError(f"{self.where}: parameter {name!r} must be one of "
                                     f"{declared[name].choices}, got {value!r}")
                plain[name] = value
            else:
                plain[name] = plain_number_tree(value, f"{self.where}, parameter {name!r}")
        return plain

    def generate(self, rng: np.random.Generator,
                 settings: QuestionSettings | None = None) -> Variant:
        """A variant drawn from ``rng`` alone: draws until one is well posed.

        ``settings`` (an assignment's :class:`problems.settings.QuestionSettings`) fixes or
        re-ranges parameters after each draw and changes the answers' points and tolerances.

        Raises
        ------
        RuntimeError
            No acceptable draw in ``MAX_ATTEMPTS`` tries.
        """
        for _ in range(self.max_attempts):
            drawn = self.accepted(rng, settings)
            if drawn is not None:
                params, answers = drawn
                if settings is not None:
                    answers = settings.adjust_answers(answers)
                return self._variant(params, answers)
        raise RuntimeError(f"{self.name}: no acceptable draw in {self.max_attempts} attempts")

    def generate_many(self, rngs: Sequence[np.random.Generator],
                      settings: QuestionSettings | None = None) -> list[Variant]:
        """:meth:`generate` for each generator — the same variants — drawn together: each
        round draws once for every student still without a well-posed draw (:meth:`draw_many`)
        and answers all of them at once (:meth:`answers_many`), up to ``MAX_ATTEMPTS`` rounds.

        Raises
        ------
        RuntimeError
            A student without an acceptable draw in ``MAX_ATTEMPTS`` tries.
        """
        rngs = list(rngs)
        found: list[tuple[dict[str, Any], tuple[Answer, ...]] | None] = [None] * len(rngs)
        pending = list(range(len(rngs)))
        for _ in range(self.max_attempts):
            for i, drawn in zip(pending, self.accepted_many([rngs[i] for i in pending],
                                                            settings), strict=True):
                found[i] = drawn
            pending = [i for i in pending if found[i] is None]
            if not pending:
                return [self._variant(params, answers if settings is None
                                     else settings.adjust_answers(answers))
                        for params, answers in found]
        raise RuntimeError(f"{self.name}: no acceptable draw in {self.max_attempts} attempts")

    def accepted_many(self, rngs: Sequence[np.random.Generator],
                      settings: QuestionSettings | None = None
                      ) -> list[tuple[dict[str, Any], tuple[Answer, ...]] | None]:
        """:meth:`accepted` of each generator, the draws and the answers each made at once."""
        drawn = [None if params is None else self._adjusted(params, rng, settings)
                 for params, rng in zip(self.draw_many(rngs), rngs, strict=True)]
        shown = [params for params in drawn if params is not None]
        answered = iter(self.answers_many(shown))
        accepted: list[tuple[dict[str, Any], tuple[Answer, ...]] | None] = []
        for params in drawn:
            answers = None if params is None else next(answered)
            ok = answers is not None and not isinstance(answers, IllPosed)
            accepted.append((params, self.with_written(params, answers, settings)) if ok
                            else None)
        return accepted

    def _adjusted(self, params: dict[str, Any], rng: np.random.Generator,
                  settings: QuestionSettings | None) -> dict[str, Any] | None:
        """A draw with the settings applied (None: rejected), as the family records it."""
        if settings is not None:
            params = unless_ill_posed(settings.adjust_parameters, params, self, rng)
            if isinstance(params, IllPosed):
                return None
        return None if params is None else self.recorded(params)

    def accepted(self, rng: np.random.Generator, settings: QuestionSettings | None = None
                 ) -> tuple[dict[str, Any], tuple[Answer, ...]] | None:
        """One attempt: ``(params, answers)``, or None when the draw was rejected."""
        try:
            params = self.draw(rng)
            if params is not None and settings is not None:
                params = settings.adjust_parameters(params, self, rng)
            if params is None:
                return None
            params = self.recorded(params)
            return params, self.asked(params, settings)
        except IllPosed:
            return None


def unless_ill_posed(function: Callable, *args: Any) -> Any:
    """``function(*args)``, or the :class:`IllPosed` it raised (an element of a batch form's
    result), without its traceback: kept, it would hold the frames that hold the batch (a
    cycle, which only the cycle collector frees, walking through the whole batch)."""
    try:
        return function(*args)
    except IllPosed as e:
        return e.with_traceback(None)


def check_contract(module: Any, where: str) -> None:
    """Raise :class:`FamilyError` naming ``where`` unless ``module`` keeps the contract."""
    missing = [attr for attr in _REQUIRED if not hasattr(module, attr)]
    if missing:
        raise FamilyError(f"{where}: a family must define {', '.join(missing)} "
                          "(problems/API.md, 'A family')")
    name = module.NAME
    if not isinstance(name, str) or not name.isidentifier():
        raise FamilyError(f"{where}: NAME must be a Python identifier, got {name!r}")
    for attr in ("TITLE", "SUMMARY"):
        text = getattr(module, attr)
        if not isinstance(text, str) or not text.strip() or "\n" in text:
            raise FamilyError(f"{where}: {attr} must be one line of text, got {text!r}")
    for attr in ("answers", "statement", "draw", "heading", "prepare", "follow", "degenerate",
                 "written", "draw_many", "answers_many"):
        if hasattr(module, attr) and not callable(getattr(module, attr)):
            raise FamilyError(f"{where}: {attr} must be a function")
    from problems.conventions import TOPICS

    unknown = [t for t in getattr(module, "CONVENTIONS", ()) if t not in TOPICS]
    if unknown:
        raise FamilyError(f"{where}: CONVENTIONS {unknown} are not topics of the notebook's "
                          f"conventions ({', '.join(TOPICS)})")
    parameters = module.PARAMETERS
    if not isinstance(parameters, Mapping):
        raise FamilyError(f"{where}: PARAMETERS must be a dict of name -> Parameter")
    for key, p in parameters.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise FamilyError(f"{where}: PARAMETERS: {key!r} is not a Python identifier")
        if not isinstance(p, Parameter):
            raise FamilyError(f"{where}: PARAMETERS[{key!r}] must be a Parameter, got {p!r}")
        if not hasattr(module, "draw") and not p.settable:
            raise FamilyError(f"{where}: PARAMETERS[{key!r}] has neither a range nor choices; "
                              "give it low and high, or define draw(rng)")
