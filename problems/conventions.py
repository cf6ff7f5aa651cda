"""Conventions stated once at the top of a student's notebook, not in every question.

A notebook opens with :data:`GENERAL` (units, angles, how answers are named and compared) and
then the topic paragraphs of :data:`TOPICS` that its questions use: a template lists the topics
it relies on in its module attribute ``CONVENTIONS`` (a tuple of keys of :data:`TOPICS`), and
its statement then speaks of "the Euler angles" without repeating their definition.
How one particular answer is compared (its tolerance) is derived from the answer itself by
:func:`problems.answers.comparison_rule` and stated in its question.
"""

from __future__ import annotations

from collections.abc import Iterable

GENERAL = """\
**Conventions for every question**

- **Units**: SI throughout (kg, m, s, N, J); angles in **radians**, rates in rad/s.
- **Answers** go into the variables `q{k}_{name}` of question k's answer cell, where each \
line's comment gives its unit and what it is. Vectors are lists or arrays in the stated \
order. Each answer is worth 1 point unless its line says otherwise.
- **How answers are compared** (each question states its tolerances): a number is correct \
within a *relative* tolerance, |yours − key| ≤ rtol·|key|; where a question also gives an \
*absolute* tolerance (for values that may be near zero) the two add. A vector is compared \
on the length of the difference, ‖yours − key‖ ≤ rtol·‖key‖. An angle is compared as a \
number in radians, in the range the question asks for; it is taken modulo 2π only where its \
question says so. True/False and named options must match exactly (case is ignored). \
Keep at least five significant figures: an answer rounded to fewer can fall outside \
a 0.1 % tolerance.\
"""

TOPICS: dict[str, str] = {
    "inertia": """\
**Inertia tensor.** $I_{xx} = \\sum m (y^2 + z^2)$ and cyclically; the **products of \
inertia** are the off-diagonal entries with their minus sign, \
$I_{xy} = -\\sum m\\,x y$, $I_{xz} = -\\sum m\\,x z$, $I_{yz} = -\\sum m\\,y z$ (integrals for \
a continuous body), so that $\\mathbf L = \\mathsf I\\,\\boldsymbol\\omega$ and \
$T = \\tfrac12 \\boldsymbol\\omega\\cdot\\mathsf I\\,\\boldsymbol\\omega$.\
""",
    "euler_angles": """\
**Euler angles** (as in the lecture). The body frame is reached from the lab frame by turning \
through $\\alpha$ about the lab $z$ axis, then through $\\beta$ about the new $y'$ axis, then \
through $\\gamma$ about the body axis $\\hat e_3$; $\\beta$ is the tilt of $\\hat e_3$ from the \
**upward** vertical. A vector with lab components $V$ has body components $V' = R\\,V$ with \
$R = R_\\gamma R_\\beta R_\\alpha$,

$$R_\\alpha = \\begin{pmatrix} \\cos\\alpha & \\sin\\alpha & 0 \\\\ -\\sin\\alpha & \\cos\\alpha \
& 0 \\\\ 0 & 0 & 1 \\end{pmatrix},\\quad
R_\\beta = \\begin{pmatrix} \\cos\\beta & 0 & -\\sin\\beta \\\\ 0 & 1 & 0 \\\\
\\sin\\beta & 0 & \\cos\\beta \\end{pmatrix},\\quad
R_\\gamma = \\begin{pmatrix} \\cos\\gamma & \\sin\\gamma & 0 \\\\ -\\sin\\gamma & \\cos\\gamma \
& 0 \\\\ 0 & 0 & 1 \\end{pmatrix}.$$

The spin about the symmetry axis is $\\omega_3 = \\dot\\gamma + \\dot\\alpha\\cos\\beta$, not \
$\\dot\\gamma$ alone.\
""",
    "heavy_top": """\
**Heavy symmetric top.** The symmetry axis $\\hat e_3$ points from the fixed point (tip, \
pivot) to the centre of mass, a distance $l$ from it; $\\alpha$ is the azimuth of the axis \
about the vertical (precession, positive counter-clockwise seen from above), $\\beta$ its tilt \
from the **upward** vertical, $\\gamma$ the spin angle about $\\hat e_3$ (right-handed). \
$I_1$ is the moment of inertia about an axis through the **fixed point** perpendicular to the \
symmetry axis (unless a question says otherwise), $I_3$ the moment about the symmetry axis; \
the potential energy is $Mgl\\cos\\beta$ (zero at the height of the fixed point).\
""",
    "free_body": """\
**Free rigid body.** No torque acts about the centre of mass (ignore air). Principal axes \
$\\hat e_1, \\hat e_2, \\hat e_3$ form a right-handed body frame; "body-frame components" are \
components along them.\
""",
}


def conventions_text(topics: Iterable[str]) -> str:
    """:data:`GENERAL`, then each of ``topics`` once, in the order of :data:`TOPICS`.

    Raises ``KeyError`` for an unknown topic (a template bug).
    """
    wanted = set(topics)
    unknown = sorted(wanted - set(TOPICS))
    if unknown:
        raise KeyError(f"unknown convention topics {unknown}; known: {sorted(TOPICS)}")
    return "\n\n".join([GENERAL, *(text for key, text in TOPICS.items() if key in wanted)])
