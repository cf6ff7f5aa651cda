"""Sources of families written outside the package, as an instructor would write them against
the documented API (``from eulertop.family import ...``), for the tests of loading, specs and
the self-test.

``PENDULUM`` is a uniform rod swinging about one end (R2 with the parallel-axis theorem:
``I = m L²/3``; small oscillations ``T = 2π √(I/(m g L/2)) = 2π √(2L/(3g))``).
"""

from __future__ import annotations

from pathlib import Path

PENDULUM = '''\
"""A uniform rod swinging about one end."""
import math

from eulertop.family import Answer, Mistake, Parameter

NAME = "{name}"
TITLE = "A rod swinging about one end"
SUMMARY = "physical pendulum: moment of inertia about the pivot, period of small swings"
PARAMETERS = {{
    "L": Parameter(unit="m", low=0.2, high=2.0, figures=3, description="length"),
    "m": Parameter(unit="kg", low=0.1, high=1.0, figures=3, description="mass"),
    "g": Parameter(unit="m/s^2", low=9.81, high=9.81, figures=3),
}}


def answers(p):
    L, m, g = p["L"], p["m"], p["g"]
    inertia = m * L**2 / 3
    period = 2 * math.pi * math.sqrt(inertia / (m * g * L / 2))
    return (
        Answer("I", "scalar", inertia, unit="kg m^2", description="moment about the pivot",
               mistakes=(Mistake("about_centre", m * L**2 / 12, "That is about the centre."),)),
        Answer("T", "scalar", period, unit="s", description="period of small swings",
               mistakes=(Mistake("simple_pendulum", 2 * math.pi * math.sqrt(L / g),
                                 "That is a point mass at the end of the rod."),)),
    )


def statement(p):
    return (
        f"A uniform rod of length $L = {{p['L']:g}}$ m (`L`) and mass $m = {{p['m']:g}}$ kg "
        f"(`m`) swings about one end; $g = {{p['g']:g}}$ m/s² (`g`).\\n\\n"
        "1. `I`: its moment of inertia about the pivot;\\n"
        "2. `T`: its period for small swings."
    )
'''


def pendulum(name: str = "physical_pendulum") -> str:
    """The pendulum family's source, called ``name``."""
    return PENDULUM.format(name=name)


def write_family(folder: Path, file: str, text: str) -> Path:
    """Write ``text`` to ``folder/file`` (folders made as needed); the path."""
    path = Path(folder) / file
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path
