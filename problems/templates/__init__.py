"""The catalogue of problem families: ``FAMILIES[name]`` is the template module ``name``.

Each template is a module ``problems/templates/<name>.py`` defining ``NAME`` (equal to the module
name), ``TITLE``, ``SUMMARY``, ``RESULTS`` (R-ids of ``physics.md``) and a pure
``generate(rng: numpy.random.Generator) -> Variant`` (contract: ``problems/API.md``).
To add a family, write the module and append its name to :data:`CATALOGUE`; the catalogue's
order is the order of ``eulertop problems`` and of the default ``--problems`` list.
"""

from __future__ import annotations

from importlib import import_module
from types import ModuleType

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

_REQUIRED = ("NAME", "TITLE", "SUMMARY", "RESULTS", "generate")


def _load(name: str) -> ModuleType:
    module = import_module(f"{__name__}.{name}")
    missing = [attr for attr in _REQUIRED if not hasattr(module, attr)]
    if missing:
        raise ImportError(f"template {module.__name__} lacks {', '.join(missing)}")
    if module.NAME != name:
        raise ImportError(f"template {module.__name__} has NAME {module.NAME!r}, expected {name!r}")
    return module


FAMILIES: dict[str, ModuleType] = {name: _load(name) for name in CATALOGUE}
