"""The built-in problem families: ``FAMILIES[name]`` is the :class:`~problems.family.Family` of
the module ``problems/templates/<name>.py``.

Each module keeps the family contract (``problems/API.md``, :mod:`problems.family`): ``NAME``
(equal to the module name), ``TITLE``, ``SUMMARY``, ``RESULTS`` (R-ids of
``docs/physics/index.md``), ``PARAMETERS``, ``draw``, ``answers`` and ``statement``. To add one,
write the module and append its name to :data:`CATALOGUE`; the catalogue's order is the order of
``eulertop problems`` and of the default ``--problems`` list. Families from outside the package
are found by :mod:`problems.family_files`.
"""

from __future__ import annotations

from importlib import import_module

from problems.family import Family, FamilyError

# Module names, in catalogue order (the lecture's order: inertia, Euler equations, Euler angles,
# heavy top).
CATALOGUE: tuple[str, ...] = (
    "inertia_tensor",
    "energy_momentum",
    "symmetric_free_top",
    "near_axis_stability",
    "asymmetric_free_top",
    "euler_rotation",
    "euler_kinetic_energy",
    "heavy_top_constants",
    "turning_points",
    "motion_type",
    "sleeping_top",
    "nutation_precession",
    "steady_precession",
    "symbolic_derivation",
)


def _load(name: str) -> Family:
    family = Family(import_module(f"{__name__}.{name}"), origin="built-in")
    if family.name != name:
        raise FamilyError(f"{family.where}: NAME is {family.name!r}, expected {name!r}")
    if not family.results:
        raise FamilyError(f"{family.where}: a built-in family lists its RESULTS (R-ids)")
    return family


FAMILIES: dict[str, Family] = {name: _load(name) for name in CATALOGUE}
