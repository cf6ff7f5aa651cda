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

- **Units**: SI; angles in **radians**, rates in rad/s.
- **Answers**: numbers, lists or arrays (vectors, in the stated order), sympy expressions or \
strings; 1 point each unless the line says otherwise.
- **Comparison**: a percentage is a *relative* tolerance, |yours − key| ≤ rtol·|key|, an amount \
with a unit an *absolute* one (the two add); a vector is compared by the length of the \
difference, an angle in radians (modulo 2π only where stated). Keep five significant figures.\
"""

TOPICS: dict[str, str] = {
    "inertia": """\
**Inertia tensor.** $I_{xx} = \\sum m (y^2 + z^2)$ and cyclically; the **products of \
inertia** carry a minus sign, $I_{xy} = -\\sum m\\,x y$ (integrals for a continuous body), \
so that $\\mathbf L = \\mathsf I\\,\\boldsymbol\\omega$ and \
$T = \\tfrac12 \\boldsymbol\\omega\\cdot\\mathsf I\\,\\boldsymbol\\omega$.\
""",
    "euler_angles": """\
**Euler angles** (as in the lecture): the body frame is the lab frame turned by $\\alpha$ about \
the lab $z$ axis, then by $\\beta$ about the new $y'$ axis, then by $\\gamma$ about the body \
axis $\\hat e_3$; $\\beta$ is the tilt of $\\hat e_3$ from the **upward** vertical. Lab \
components $V$ become body components $V' = R\\,V$, $R = R_\\gamma R_\\beta R_\\alpha$,

$$R_\\alpha = \\begin{pmatrix} \\cos\\alpha & \\sin\\alpha & 0 \\\\ -\\sin\\alpha & \\cos\\alpha \
& 0 \\\\ 0 & 0 & 1 \\end{pmatrix},\\quad
R_\\beta = \\begin{pmatrix} \\cos\\beta & 0 & -\\sin\\beta \\\\ 0 & 1 & 0 \\\\
\\sin\\beta & 0 & \\cos\\beta \\end{pmatrix},\\quad
R_\\gamma = \\begin{pmatrix} \\cos\\gamma & \\sin\\gamma & 0 \\\\ -\\sin\\gamma & \\cos\\gamma \
& 0 \\\\ 0 & 0 & 1 \\end{pmatrix}.$$

The spin about the symmetry axis is $\\omega_3 = \\dot\\gamma + \\dot\\alpha\\cos\\beta$.\
""",
    "heavy_top": """\
**Heavy symmetric top.** $\\hat e_3$ points from the fixed point to the centre of mass, $l$ \
away; $\\alpha$ is its azimuth (counter-clockwise seen from above), $\\beta$ its tilt from the \
**upward** vertical. $I_1$ is the moment about a transverse axis through the **fixed point** \
(unless a question says otherwise), $I_3$ about $\\hat e_3$; the potential energy is \
$Mgl\\cos\\beta$.\
""",
    "free_body": """\
**Free rigid body.** No torque acts about the centre of mass; the principal axes \
$\\hat e_1, \\hat e_2, \\hat e_3$ form a right-handed body frame ("body components" are \
along them).\
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
