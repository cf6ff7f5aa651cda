"""The bottom floor every part stands on, shipped by both distributions: the full ``eulertop``
and the student's ``eulertop-check`` (``student/pyproject.toml``, issue 33), which holds no
solver. It holds only :class:`ParameterError`, the error every part raises for a value that is
missing, not a number or outside its domain: the solver's parameters, an answer's fields, a
run's limits — one class, so that ``except ParameterError`` catches it from any of them.
"""

from __future__ import annotations

__all__ = ["ParameterError"]


class ParameterError(ValueError):
    """A physical parameter is missing, not a number, or outside its domain.

    Attributes
    ----------
    parameter : str
        The name of the offending parameter, as the user wrote it (``"I1"``, ``"omega0"``).
    """

    def __init__(self, parameter: str, message: str) -> None:
        super().__init__(f"{parameter}: {message}")
        self.parameter = parameter
