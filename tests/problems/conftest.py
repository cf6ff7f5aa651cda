"""Fixtures for the generator's tests: a test-only problem family and roster files.

The family (kept to the family contract, ``problems/API.md``) is a tilted thin rod (R2: a
uniform rod of mass m and length L whose axis makes the angle θ with the rotation axis through
its centre has I = m L² sin²θ / 12). It has one answer of every kind, all computed from the
*displayed* (rounded) parameters, so the generator's tests do not depend on the real templates.
"""

from __future__ import annotations

import math
import types
from pathlib import Path

import pytest

from problems import templates
from problems.answers import Answer, Mistake
from problems.family import Family, Parameter, draw_parameters


def make_rod_family(name: str = "rod", fail_on_call: int | None = None) -> Family:
    """A family kept as a namespace; ``fail_on_call=n`` makes the n-th draw raise."""
    calls = {"n": 0}
    parameters = {"m": Parameter(unit="kg", low=0.1, high=2.0),
                  "L": Parameter(unit="m", low=0.2, high=1.5),
                  "θ": Parameter(unit="rad", low=0.3, high=1.3)}

    def draw(rng) -> dict:
        calls["n"] += 1
        if fail_on_call is not None and calls["n"] == fail_on_call:
            raise RuntimeError("test template exploded")
        return draw_parameters(rng, parameters)  # displayed to 3 significant figures

    def answers(p) -> tuple[Answer, ...]:
        m, L, θ = p["m"], p["L"], p["θ"]  # the answers use the displayed values
        I_c = m * L**2 / 12
        I_tilt = I_c * math.sin(θ) ** 2
        return (
            Answer("I_c", "scalar", I_c, unit="kg m^2", description="moment about the centre",
                   mistakes=(Mistake("end_axis", m * L**2 / 3, "that is about the end"),)),
            Answer("I_tilt", "scalar", I_tilt, unit="kg m^2", description="about the tilted axis"),
            Answer("r_cm", "vector", [0.0, L / 2, L / 4], unit="m", description="a test vector"),
            Answer("theta", "angle", θ + 2 * math.pi, unit="rad", period=2 * math.pi,
                   mistakes=(Mistake("supplement", math.pi - θ, "that is π − θ"),)),
            Answer("centre_smaller", "boolean", True, description="is I_c below I_end?"),
            Answer("bigger", "choice", "end", options=("centre", "end"),
                   description="which axis has the larger moment"),
            Answer("I_expr", "expression", "m*L**2*sin(theta)**2/12",
                   symbols=("m", "L", "theta"), description="I about the tilted axis"),
        )

    def statement(p) -> str:
        return (f"A thin uniform rod of mass $m = {p['m']}$ kg and length $L = {p['L']}$ m turns "
                f"about an axis through its centre at $\\theta = {p['θ']}$ rad to the rod.")

    return Family(types.SimpleNamespace(
        NAME=name, TITLE="Moment of inertia of a thin rod",
        SUMMARY="moment of inertia of a thin rod (test only)", RESULTS=("R2",),
        PARAMETERS=parameters, draw=draw, answers=answers, statement=statement,
    ), origin="test")


@pytest.fixture
def families(monkeypatch) -> dict:
    """Register two test families, ``rod`` and ``rod2``, in ``problems.templates.FAMILIES``."""
    for name in ("rod", "rod2"):
        monkeypatch.setitem(templates.FAMILIES, name, make_rod_family(name))
    return templates.FAMILIES


@pytest.fixture
def write_roster(tmp_path):
    """``write_roster(text_or_bytes, name="roster.csv") -> Path`` in a scratch folder."""
    folder = tmp_path / "input"
    folder.mkdir()

    def write(content: str | bytes, name: str = "roster.csv") -> Path:
        path = folder / name
        if isinstance(content, str):
            path.write_text(content, encoding="utf-8")
        else:
            path.write_bytes(content)
        return path

    return write


ROSTER = "id,name,email\nalice,Alice Ng,alice@uni.example\nbob,Bob Roy,bob@uni.example\n" \
         "carol,Carol Dee,carol@uni.example\n"


@pytest.fixture
def roster_path(write_roster) -> Path:
    """A valid three-student roster."""
    return write_roster(ROSTER)


def _read_tree(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


@pytest.fixture
def read_tree():
    """``read_tree(folder) -> {relative path: bytes}`` of every file under ``folder``."""
    return _read_tree
