"""The problem-family API, for families written outside eulertop (``problems/API.md``).

A family is one Python file (or package) that defines ``NAME``, ``TITLE``, ``SUMMARY``,
``PARAMETERS`` (a dict of :class:`Parameter`), ``answers(params)`` (a tuple of :class:`Answer`,
each with its known :class:`Mistake` s) and ``statement(params)``, and optionally ``draw(rng)``
(default: :func:`draw_parameters`). An answer the statement asks to compute from earlier ones
is declared with :func:`follows_from`, and ``follow(name, params, earlier)`` recomputes it from
a student's own earlier values (follow-through credit); ``degenerate(name, params, earlier)``
may say why such values leave nothing to work out (one line, or None), beside the defaults
every family gets (:mod:`problems.genuine`; :func:`statement_number` names a parameter a value
copies). A family may offer written parts — a derivation or an explanation the student writes
in Markdown, scored by a person against a rubric — with ``written(params)`` returning
:class:`Written` records; an assignment spec asks for them (``written = true``).
``draw_many(rngs)`` and ``answers_many(params_list)`` are an optional batch form: the same
draws and answers for many students at once, a rejected one None or an :class:`IllPosed`
(``problems/API.md``). ``eulertop new-family NAME --out DIR`` writes a working, commented
example; ``eulertop problems test FILE`` checks one.

Examples
--------
>>> from eulertop.family import Answer, Mistake, Parameter
>>> Parameter(unit="m", low=0.2, high=2.0, figures=3).settable
True
"""

from __future__ import annotations

from problems.answers import Answer, Mistake, RubricItem
from problems.family import IllPosed, Parameter, draw_parameters, follows_from
from problems.genuine import statement_number
from problems.written import Written

__all__ = ["Answer", "IllPosed", "Mistake", "Parameter", "RubricItem", "Written",
           "draw_parameters", "follows_from", "statement_number"]
