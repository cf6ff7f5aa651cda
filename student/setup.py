"""The student package is built from modules of this repository, listed here, and no others
(issue 33): each file is the repository's own, not a copy, so the check a student runs is the
grader's. Everything else of the repository — the solver, the problem families, the key, the
comparison with it, the records and the report — stays out (``tests/grader/test_student_package.py``
builds the wheel and checks its list).
"""

from setuptools import setup
from setuptools.command.build_py import build_py

SHIPPED = {
    "eulertop_base": ["__init__"],
    "eulertop_check": ["__init__", "cli", "live", "show", "where"],
    "grader": ["__init__", "check", "execute", "extract", "limits", "notebook_load",
               "notebook_metadata", "run_file", "submission_file", "student_text", "written"],
    "grader.kernels": ["__init__", "base", "cell_server", "channel", "local", "pool", "zygote"],
    "grader.sandbox": ["__init__", "host", "seccomp", "world"],
    "problems": ["__init__", "answers", "expressions"],
}
"""Package → its modules the student package holds."""


class ListedModulesOnly(build_py):
    """setuptools' build_py, keeping of each package only the modules in :data:`SHIPPED`."""

    def find_package_modules(self, package, package_dir):
        found = super().find_package_modules(package, package_dir)
        return [entry for entry in found if entry[1] in SHIPPED.get(package, ())]


setup(
    cmdclass={"build_py": ListedModulesOnly},
    package_dir={"": ".."},
    packages=list(SHIPPED),
    package_data={"grader.sandbox": ["apparmor/eulertop-bwrap"]},
    include_package_data=False,
)
