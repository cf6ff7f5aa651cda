"""A ball thrown over level ground: an example problem family for eulertop.

``eulertop new-family NAME --out DIR`` copies this file to ``DIR/NAME.py`` with its ``NAME``
changed. It keeps the whole family contract (eulertop's ``problems/API.md``, "A family"), and
passes ``eulertop problems test DIR/NAME.py`` as it is. Edit it into your own problem:

1. say what the student is given, in ``PARAMETERS`` (ranges, units, significant figures);
2. compute the key from those values alone, in ``answers`` — with the mistakes you expect, so
   that the feedback can name them;
3. write what the student reads, in ``statement``;
4. run ``eulertop problems test DIR/NAME.py`` and ``eulertop problems preview DIR/NAME.py``;
5. use it: ``eulertop generate --families DIR --problems NAME,...`` or ``families = ["DIR"]``
   in an assignment spec.
"""

from __future__ import annotations

import math

from eulertop.family import Answer, IllPosed, Mistake, Parameter, draw_parameters

# The family's name: how --problems and a spec call it. It must be a Python identifier and may
# not be the name of a built-in family (`eulertop problems` lists them).
NAME = "projectile"
# The question's title, and one line for `eulertop problems`.
TITLE = "A ball thrown over level ground"
SUMMARY = "projectile over level ground: range, time of flight, greatest height"

# What the student is given. Each number is drawn uniformly in [low, high] and rounded to
# `figures` significant figures; the answers are then computed from the rounded values, the
# ones the student reads. Each becomes a variable of the student's parameter cell, `q1_v0`
# (`cell=False` would only write it into the statement). An assignment spec may fix a
# parameter or narrow its range, within [low, high].
PARAMETERS = {
    "v0": Parameter(unit="m/s", low=5.0, high=30.0, figures=3, description="launch speed"),
    "theta": Parameter(unit="rad", low=0.2, high=1.3, figures=3,
                       description="launch angle above the horizontal"),
    # A constant is a parameter with low == high: it is shown, and in the parameter cell.
    "g": Parameter(unit="m/s^2", low=9.81, high=9.81, figures=3,
                   description="gravitational acceleration"),
}

RTOL = 1e-3
"""Relative tolerance of every answer: the data are exact 3-figure numbers, and each answer
is one closed form of them, so any careful computation lands far inside it."""


def draw(rng):
    """Optional: without it, every parameter is drawn as PARAMETERS says (draw_parameters).

    Draw from `rng` only (never from `random` or the clock), so that a seed always gives the
    same variant. Return None to reject an ill-posed draw: the generator draws again.
    """
    params = draw_parameters(rng, PARAMETERS)
    v0, theta, g = params["v0"], params["theta"], params["g"]
    if (v0 * math.sin(theta)) ** 2 / (2 * g) < 1.0:
        return None  # a throw lower than a metre: not worth the question
    return params


def answers(params):
    """The key, from `params` alone (the recorded parameters recompute it later).

    Raise IllPosed when these parameters make no good question, here when a known mistake
    would be graded right: sin θ and cos θ nearly equal (θ near π/4).
    """
    v0, theta, g = params["v0"], params["theta"], params["g"]
    if abs(math.tan(theta) - 1.0) < 0.02:
        raise IllPosed("θ too close to π/4: sin and cos swapped would look right")
    rate = v0 * math.sin(theta)  # the vertical launch speed
    flight = 2 * rate / g
    reach = v0**2 * math.sin(2 * theta) / g
    height = rate**2 / (2 * g)
    return (
        # Each answer: its variable's suffix (q1_T), kind, key, unit, tolerance, and the known
        # mistakes with what the student is told when the grader recognises one.
        Answer("T", "scalar", flight, unit="s", rtol=RTOL, description="time of flight",
               mistakes=(
                   Mistake("apex_time", rate / g, "That is the time to the top of the "
                           "flight; the ball takes as long again to come down."),
                   Mistake("sin_cos_swapped", 2 * v0 * math.cos(theta) / g, "The vertical "
                           "launch speed is v0 sin θ, not v0 cos θ (θ is above the horizontal)."),
               )),
        Answer("R", "scalar", reach, unit="m", rtol=RTOL, description="range on level ground",
               mistakes=(
                   Mistake("degrees", v0**2 * math.sin(2 * math.radians(theta)) / g,
                           "θ is in radians; this value comes from reading it as degrees."),
               )),
        Answer("H", "scalar", height, unit="m", rtol=RTOL, points=0.5,
               description="greatest height above the ground",
               mistakes=(
                   Mistake("missing_half", 2 * height, "H = (v0 sin θ)²/(2g): the 2 in the "
                           "denominator is missing."),
               )),
    )


def statement(params):
    """What the student reads: Markdown with LaTeX. Name each parameter's variable in
    backticks; never write a tolerance (the notebook states how each answer is compared) and
    never a number computed from the answers."""
    v0, theta, g = params["v0"], params["theta"], params["g"]
    return (
        f"A ball is thrown from level ground at $v_0 = {v0:g}$ m/s (`v0`), at the angle "
        f"$\\theta = {theta:g}$ rad (`theta`) above the horizontal. Take $g = {g:g}$ m/s² "
        "(`g`) and ignore the air.\n\n"
        "1. `T`: how long the ball is in the air (s);\n"
        "2. `R`: how far from the thrower it lands (m);\n"
        "3. `H`: the greatest height it reaches (m)."
    )
