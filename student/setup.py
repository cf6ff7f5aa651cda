"""The student package is built from modules of this repository, listed here, and no others
(issue 33): each file is the repository's own, not a copy kept by hand, so the check a student
runs is the grader's. Everything else of the repository — the solver, the problem families, the
key, the comparison with it, the records and the report — stays out
(``tests/grader/test_student_package.py`` builds the wheel and checks its list).

The wheel installs ONE top-level package, ``eulertop_check``. The modules it shares with the
full ``eulertop`` (of ``grader``, ``problems`` and ``eulertop_base``) are placed by the build
under ``eulertop_check/_shared/``, under their own names there; ``eulertop_check/__init__.py``
makes them importable where no other ``grader`` is (``sys.path`` appended, never prepended).
So no file is installed by both distributions, and neither hides the other's modules.
"""

import shutil

from setuptools import setup
from setuptools.command.build_py import build_py

OWN = {"eulertop_check": ["__init__", "cli", "live", "show", "where"]}
"""The student package's own modules."""

SHARED = {
    "eulertop_base": ["__init__"],
    "grader": ["__init__", "check", "execute", "extract", "limits", "notebook_load",
               "notebook_metadata", "run_file", "submission_file", "student_text", "written"],
    "grader.kernels": ["__init__", "base", "cell_server", "channel", "local", "pool", "zygote"],
    "grader.sandbox": ["__init__", "host", "seccomp", "world"],
    "problems": ["__init__", "answers", "expressions"],
}
"""Package → its modules the student package holds of the repository's shared ones."""

INSIDE = "eulertop_check._shared."
"""Where the shared packages are placed (a folder ``eulertop_check/__init__.py`` puts on
``sys.path``, not a package)."""

SHIPPED = {**OWN, **{INSIDE + package: modules for package, modules in SHARED.items()}}
"""Package as installed → its modules."""


class ListedModulesOnly(build_py):
    """setuptools' build_py, keeping of each package only the modules in :data:`SHIPPED`, in
    a build folder emptied first (the wheel takes the whole folder: a module an earlier build
    left there, or an earlier layout, would be shipped too)."""

    def run(self):
        shutil.rmtree(self.build_lib, ignore_errors=True)
        super().run()

    def find_package_modules(self, package, package_dir):
        found = super().find_package_modules(package, package_dir)
        return [entry for entry in found if entry[1] in SHIPPED.get(package, ())]


setup(
    cmdclass={"build_py": ListedModulesOnly},
    package_dir={package: "../" + package.removeprefix(INSIDE).replace(".", "/")
                 for package in SHIPPED},
    packages=list(SHIPPED),
    package_data={INSIDE + "grader.sandbox": ["apparmor/eulertop-bwrap"]},
    include_package_data=False,
)
