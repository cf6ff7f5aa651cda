"""What the zygotes preload for a class: what its notebooks' code imports
(grader/kernels/pool.py ``packages_imported``, ``preload_for``; grader/pipeline.py).

References: notebooks written here with known import lines, and ``sys.modules`` read inside a
forked kernel (by the submission, before it imports anything itself).
"""

from __future__ import annotations

import contextlib
import json
import shutil
import time
from pathlib import Path

import nbformat
import pytest
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from grader import pipeline
from grader.execute import execute_submission
from grader.kernels.pool import KernelPool
from grader.kernels.preload import packages_imported, preload_for
from grader.limits import Limits
from grader.sandbox import probe
from tests.grader.test_pipeline import FakeExecute, _notebook


def notebook_bytes(*cells, markdown: str = "", as_list: bool = False) -> bytes:
    nb = new_notebook(cells=[new_markdown_cell(markdown), *map(new_code_cell, cells)])
    data = json.loads(nbformat.writes(nb))
    for cell in data["cells"]:  # lists of lines, as Jupyter writes them, or one string
        source = "".join(cell["source"]) if isinstance(cell["source"], list) else cell["source"]
        cell["source"] = source.splitlines(keepends=True) if as_list else source
    return json.dumps(data).encode()


@pytest.mark.parametrize(("cells", "expected"), [
    (["x = 1"], set()),
    (["import numpy as np"], {"numpy"}),
    (["import math, sympy as sp"], {"sympy"}),
    (["import matplotlib.pyplot as plt"], {"matplotlib"}),
    (["from scipy.integrate import solve_ivp\nimport numpy"], {"scipy", "numpy"}),
    (["def f():\n    import sympy\n    return sympy.pi"], {"sympy"}),
    (["# import sympy\nx = 'sympy'"], set()),  # neither a comment nor a string imports
    (["import sympyx", "from numpyish import y"], set()),  # other packages
])
@pytest.mark.parametrize("as_list", [False, True])
def test_only_the_code_cells_imports_count(cells, expected, as_list):
    data = notebook_bytes(*cells, markdown="Use numpy or sympy as you like.\nimport scipy",
                          as_list=as_list)
    assert packages_imported(data) == expected


@pytest.mark.parametrize("data", [b"{not json", b"[1, 2]", b'{"cells": 3}',
                                  b'{"cells": [{"cell_type": "code", "source": 5}]}'])
def test_a_notebook_that_cannot_be_read_asks_for_nothing(data):
    assert packages_imported(data) == set()


def test_numpy_always_the_rest_when_asked():
    assert preload_for(set()) == ("numpy",)
    assert preload_for({"sympy"}) == ("numpy", "sympy")
    scipy = preload_for({"scipy"})
    assert scipy[0] == "numpy" and "scipy.integrate" in scipy and "sympy" not in scipy
    assert preload_for({"matplotlib"}) == ("numpy", "matplotlib", "matplotlib.pyplot")


def test_a_kernel_of_the_pool_has_what_was_preloaded(tmp_path):
    probe = "import sys\nhad = sorted(m for m in ('numpy', 'scipy', 'sympy') if m in sys.modules)"
    path = tmp_path / "alice.ipynb"
    nbformat.write(new_notebook(cells=[new_code_cell(probe)]), path)
    limits = Limits(total_timeout=30)
    for packages, had in ((set(), ["numpy"]), ({"sympy"}, ["numpy", "sympy"])):
        with KernelPool(1, preload=preload_for(packages)) as pool:
            done = execute_submission(path, ("had",), limits, kernel_factory=pool.kernel)
        assert done.status == "ok", done.message
        assert done.answers["had"] == had


@pytest.fixture
def preloads(monkeypatch):
    """What each grading run asks its zygotes to preload (the pool itself is not started)."""
    asked = []

    @contextlib.contextmanager
    def kernels(warm, slots, sandbox=None, preload=None, early=None, work=None):
        asked.append(preload)
        yield None

    monkeypatch.setattr(pipeline, "warm_kernels", kernels)
    return asked


def test_grading_preloads_what_the_submissions_to_run_import(assignment, tmp_path, preloads):
    hw = Path(shutil.copytree(assignment, tmp_path / "HW"))
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "alice.ipynb").write_text(_notebook(hw, "alice"))  # its Markdown names sympy
    (subs / "bob.ipynb").write_text(_notebook(hw, "bob"))
    pipeline.grade_assignment(hw, subs, limits="LIMITS", execute=FakeExecute(), jobs=2)
    (subs / "bob.ipynb").write_text(_notebook(hw, "bob", "import sympy as sp"))
    pipeline.grade_assignment(hw, subs, limits="LIMITS", execute=FakeExecute(), jobs=2)
    assert preloads == [("numpy",), ("numpy", "sympy")]  # only bob ran again: his import


@pytest.fixture(scope="module")
def assignment(tmp_path_factory) -> Path:
    from tests.grader.test_pipeline import assignment as make

    return make.__wrapped__(tmp_path_factory)


def test_a_notebook_that_plots_runs_the_same_with_matplotlib_preloaded(tmp_path):
    """Same backend (the kernels' ``Agg``), same figures, same record as a Jupyter kernel."""
    from grader.kernels.local import LocalKernel

    cells = ["import matplotlib.pyplot as plt\nfig, ax = plt.subplots()\nax.plot([1, 2, 3])\n"
             "plt.show()\nbackend = plt.get_backend()", "plt.figure()\nn = len(plt.get_fignums())"]
    path = tmp_path / "alice.ipynb"
    nbformat.write(new_notebook(cells=list(map(new_code_cell, cells))), path)
    limits = Limits(total_timeout=30)
    jupyter = execute_submission(path, ("backend", "n"), limits, kernel_factory=LocalKernel)
    with KernelPool(1, preload=preload_for({"matplotlib"})) as pool:
        forked = execute_submission(path, ("backend", "n"), limits, kernel_factory=pool.kernel)
    assert jupyter.status == forked.status == "ok", (jupyter.message, forked.message)
    assert forked.answers == jupyter.answers == {"backend": "Agg", "n": 2}
    assert forked.cell_errors == jupyter.cell_errors == ()


@pytest.mark.parametrize("settings", [
    {"sandbox": True, "cold": False, "preload": ("numpy", "sympy")},
    {"sandbox": False, "cold": True, "preload": None},
    {"sandbox": True, "cold": False, "preload": ("numpy",)},
])
def test_a_dask_worker_rebuilds_the_preload_from_the_plugins_name(settings):
    """A worker that joins after the plugin was registered makes it from its name alone."""
    from grader.executors.dask import WorkerKernels, _settings

    plugin = WorkerKernels(**settings)
    assert _settings(plugin.name) == settings
    assert plugin.name != WorkerKernels(settings["sandbox"], settings["cold"], ("scipy",)).name


# --------------------------------------------------------------------------------------------
# the zygote started before the class is read (grader/kernels/early.py, issue 34)


def _had(pool: KernelPool, tmp_path: Path) -> list[str]:
    """What a kernel of ``pool`` had imported before its submission ran (read inside it)."""
    probe = ("import sys\n"
             "had = sorted(m for m in ('numpy', 'scipy', 'sympy', 'matplotlib') "
             "if m in sys.modules)")
    path = tmp_path / "alice.ipynb"
    nbformat.write(new_notebook(cells=[new_code_cell(probe)]), path)
    done = execute_submission(path, ("had",), Limits(total_timeout=30),
                              kernel_factory=pool.kernel)
    assert done.status == "ok", done.message
    return done.answers["had"]


def test_an_early_zygote_imports_the_rest_of_the_preload_once_told(tmp_path):
    with KernelPool(1, sandbox=probe(), early=True) as pool:
        zygote = pool.slots[0].zygote
        assert zygote is not None and zygote.ready is None  # started at once, waiting
        pool.plan(2, preload_for({"sympy"}))
        assert _had(pool, tmp_path) == ["numpy", "sympy"]  # told after its start: in too
        assert zygote.ready["preloaded"] == ["IPython", "numpy", "sympy"]
        assert len(pool.slots) == 2 and pool.slots[1].preload == ("numpy", "sympy")
        assert pool.slots[0].preload == ("IPython", "numpy", "sympy")  # if started again


def test_an_early_zygote_never_told_ends_with_the_pool(tmp_path):
    pool = KernelPool(1, sandbox=probe(), early=True)
    zygote = pool.slots[0].zygote
    time.sleep(3)  # its first imports done: waiting on its input for the rest
    began = time.monotonic()
    pool.close()
    assert time.monotonic() - began < 2  # end of input ends it: no timeout, no kill needed
    assert zygote.process.poll() is not None and zygote.ready is None
    assert not pool.folder.exists()


def test_a_grading_run_forks_its_kernels_from_the_early_zygote(assignment, tmp_path):
    hw = Path(shutil.copytree(assignment, tmp_path / "HW"))
    subs = tmp_path / "subs"
    subs.mkdir()
    (subs / "alice.ipynb").write_text(_notebook(hw, "alice", "import sympy as sp"))
    with KernelPool(1, sandbox=probe(), early=True) as early:
        report = pipeline.grade_assignment(hw, subs, jobs=2, early=early)
        zygote = early.slots[0].zygote
        assert early.forks >= 2  # the preflight's kernel and alice's, at least
        assert zygote.ready["preloaded"] == ["IPython", "numpy", "sympy"]
        assert len(early.slots) == 1  # two jobs, one submission: one slot
    assert zygote.process.poll() is not None  # ended (by the run, waited for by its owner)
    assert not early.folder.exists()
    alice = next(r for r in report.results if r.student_id == "alice")
    assert alice.status == "graded" and alice.points == alice.max_points, alice.message
    assert alice.sandboxed
