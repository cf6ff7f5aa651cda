"""The problem-family API, for families written outside eulertop (``problems/API.md``).

A family is one Python file (or package) that defines ``NAME``, ``TITLE``, ``SUMMARY``,
``PARAMETERS`` (a dict of :class:`Parameter`), ``answers(params)`` (a tuple of :class:`Answer`,
each with its known :class:`Mistake` s) and ``statement(params)``, and optionally ``draw(rng)``
(default: :func:`draw_parameters`). An answer the statement asks to compute from earlier ones
is declared with :func:`follows_from`, and ``follow(name, params, earlier)`` recomputes it from
a student's own earlier values (follow-through credit). ``draw_many(rngs)`` and
``answers_many(params_list)`` are an optional batch form: the same draws and answers for many
students at once, a rejected one None or an :class:`IllPosed` (``problems/API.md``).
``eulertop new-family NAME --out DIR`` writes a working, commented example; ``eulertop
problems test FILE`` checks one.

Examples
--------
>>> from eulertop.family import Answer, Mistake, Parameter
>>> Parameter(unit="m", low=0.2, high=2.0, figures=3).settable
True
"""

from __future__ import annotations

from problems.answers import Answer, Mistake
from problems.family import IllPosed, Parameter, draw_parameters, follows_from

__all__ = ["Answer", "IllPosed", "Mistake", "Parameter", "draw_parameters", "follows_from"]
