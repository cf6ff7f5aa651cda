"""The student package (issue 33, ``student/``): built as a wheel and installed in a venv of its
own, once for this module (about 40 s: its dependencies come from the package index or pip's
cache), then driven as a student drives it — ``eulertop-check`` in a terminal, and
``eulertop_check.check()`` in a real kernel (jupyter_client) of that venv, found the way
JupyterLab, VS Code and a Jupyter server's sessions say where the notebook is.

References: the repository's own module list and import graph (``tests/test_layout.py``), the
full package's ``eulertop check`` run on the same notebooks, and the values the test itself
puts into the kernel."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import threading
import zipfile
from http.server import BaseHTTPRequestHandler, HTTPServer
from pathlib import Path

import pytest

from grader.submission_file import MAX_SIZE_HELP
from tests.test_layout import GRAPH, MODULES

ROOT = Path(__file__).resolve().parents[2]

NOT_SHIPPED = ("solver", "problems.templates", "problems.family", "problems.generate",
               "problems.variant", "grader.compare", "grader.assignment", "grader.grade_one",
               "grader.results", "grader.report", "grader.key_edit", "grader.pipeline",
               "eulertop")
"""What the student package must not hold: the reference solver, the families and what draws
from them, the key and the comparison with it, the records, the report, the full front end."""

OPTIONAL = {("problems.expressions", "solver.symbolic")}
"""Imports of a shipped module that may fail: ``symbol_table`` falls back to plain real
symbols when the solver's derivations are not there (``except ImportError``)."""


SHARED = "eulertop_check._shared."
"""Where the wheel holds the modules it shares with the full package (student/setup.py)."""


QUICK = ("-q", "--no-compile")
"""How these tests install with pip: quietly, and without byte-compiling what they install (half
of the time an install of the full package's dependencies takes; what is tested here does not
depend on it)."""


def _shipped(wheel: Path) -> set[str]:
    """The repository's modules the wheel holds, by their names in the repository."""
    with zipfile.ZipFile(wheel) as z:
        names = [n for n in z.namelist() if n.endswith(".py")]
    return {n.removesuffix(".py").replace("/", ".").removesuffix(".__init__").removeprefix(SHARED)
            for n in names}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out),
                    str(ROOT / "student")], check=True, capture_output=True, timeout=300)
    (found,) = out.glob("eulertop_check-*.whl")
    return found


@pytest.fixture(scope="module")
def venv(wheel, tmp_path_factory) -> Path:
    """A venv holding the student package and its dependencies, and nothing of eulertop."""
    folder = tmp_path_factory.mktemp("student-venv")
    subprocess.run([sys.executable, "-m", "venv", str(folder)], check=True, timeout=120)
    subprocess.run([str(folder / "bin" / "python"), "-m", "pip", "install", *QUICK, str(wheel)],
                   check=True, capture_output=True, timeout=600)
    return folder


def test_the_wheel_holds_no_solver_family_key_or_report(wheel):
    shipped = _shipped(wheel)
    assert {"eulertop_check", "eulertop_check.live", "grader.execute", "grader.check",
            "problems.answers"} <= shipped
    held = sorted(m for m in shipped for bad in NOT_SHIPPED if m == bad or
                  m.startswith(bad + "."))
    assert held == []
    assert all(m in MODULES for m in shipped)  # the repository's own files, nothing else


def test_the_wheel_installs_one_top_level_package(wheel):
    """Nothing of a generic name (``grader``, ``problems``) at the top: it would collide with
    the full package's files, hide an editable install of it, or another distribution's."""
    with zipfile.ZipFile(wheel) as z:
        tops = {n.split("/")[0] for n in z.namelist()}
    assert tops == {"eulertop_check", f"{wheel.name.split('-')[0]}-0.1.0.dist-info"}


def test_every_module_the_wheel_holds_finds_what_it_imports_there(wheel):
    shipped = _shipped(wheel)
    missing = sorted((m, target) for m in shipped for target in GRAPH[m]
                     if target not in shipped and (m, target) not in OPTIONAL)
    assert missing == []


def test_nothing_of_the_full_package_imports_in_the_students_venv(venv):
    """Before ``import eulertop_check`` nothing of the repository but it imports; after it,
    what the check needs, and still nothing of the full package."""
    code = ("import importlib, json\n"
            "def tried(names):\n    out = {}\n    for name in names:\n"
            "        try:\n            importlib.import_module(name); out[name] = 'imported'\n"
            "        except ImportError as e:\n            out[name] = type(e).__name__\n"
            "    return out\n"
            "before = tried(['grader', 'problems', 'eulertop_base'])\n"
            "import eulertop_check, grader.check\n"
            f"print(json.dumps([before, tried({NOT_SHIPPED!r}), grader.check.__file__]))")
    run = subprocess.run([str(venv / "bin" / "python"), "-c", code], capture_output=True,
                         text=True, timeout=60, cwd=venv)
    assert run.returncode == 0, run.stderr
    before, after, check_file = json.loads(run.stdout)
    assert set(before.values()) == set(after.values()) == {"ModuleNotFoundError"}
    assert Path(check_file).parts[-4:] == ("eulertop_check", "_shared", "grader", "check.py")


def test_another_module_of_a_shared_name_is_named_in_one_line(venv, generated_assignment,
                                                              tmp_path):
    """A ``grader.py`` of the student's own, found first: the check says so, in one line, in
    the terminal and in the notebook."""
    (tmp_path / "grader.py").write_text("MINE = True\n", encoding="utf-8")
    env = {**_plain_env(), "PYTHONPATH": str(tmp_path)}
    run = subprocess.run([str(venv / "bin" / "eulertop-check"),
                          str(generated_assignment.release())], capture_output=True, text=True,
                         timeout=60, env=env)
    said = (f"another module named 'grader' ({tmp_path / 'grader.py'}) hides eulertop's own: "
            "rename it, or install eulertop-check in a virtual environment of its own")
    assert (run.returncode, run.stdout, run.stderr) == (2, "", f"eulertop-check: {said}\n")
    kernel = Kernel(venv, tmp_path, {}, tmp_path / "kernel-hidden.json")
    try:
        shown = kernel.run("import eulertop_check\neulertop_check.check('x.ipynb')")
    finally:
        kernel.stop()
    assert shown["error"] == [f"eulertop_check: {said}"]


def _partly(a, folder: Path) -> Path:
    """alice's solutions with her first answer a string and her second removed."""
    nb = a.notebook("solutions")
    first, second = a.variables()[:2]
    for cell in nb["cells"]:
        source = "".join(cell["source"])
        if cell["cell_type"] == "code" and first + " = " in source:
            lines = [f"{first} = '1.5'" if line.startswith(first + " = ") else
                     line for line in source.splitlines() if not line.startswith(second + " =")]
            cell["source"] = "\n".join(lines)
    path = folder / "alice.ipynb"
    path.write_text(json.dumps(nb), encoding="utf-8")
    return path


def _verdicts(out: str) -> list[str]:
    """The report's lines but the sandbox's note (whether bubblewrap ran it differs by venv)."""
    return [line for line in out.splitlines() if not line.startswith("(Ran without")]


def _stored(a, folder: Path) -> Path:
    """alice's solutions, each answer of her first question stored with ``%store``, forgotten,
    and taken back: read as the grader reads them only if ``%store`` works in its kernel."""
    nb = a.notebook("solutions")
    q1 = [v for v in a.variables() if v.startswith("q1_")]
    at = next(i for i, c in enumerate(nb["cells"]) if c["cell_type"] == "code"
              and f"{q1[0]} = " in "".join(c["source"]))
    nb["cells"].insert(at + 1, {"cell_type": "code", "metadata": {}, "outputs": [],
                                "execution_count": None, "source":
                                f"%store {' '.join(q1)}\ndel {', '.join(q1)}\n%store -r"})
    path = folder / "alice.ipynb"
    path.write_text(json.dumps(nb), encoding="utf-8")
    return path


@pytest.mark.parametrize("which", ["solutions", "release", "partly", "stored"])
def test_eulertop_check_and_the_students_command_say_the_same(venv, generated_assignment,
                                                              tmp_path, which):
    a = generated_assignment
    made = {"partly": _partly, "stored": _stored}
    path = made[which](a, tmp_path) if which in made else a.hw / which / "alice.ipynb"
    full = subprocess.run([sys.executable, "-m", "eulertop", "check", str(path)],
                          capture_output=True, text=True, timeout=300, cwd=ROOT)
    student = subprocess.run([str(venv / "bin" / "eulertop-check"), str(path)],
                             capture_output=True, text=True, timeout=300, cwd=tmp_path)
    assert student.returncode == full.returncode
    assert _verdicts(student.stdout) == _verdicts(full.stdout)
    assert full.returncode == {"solutions": 0, "release": 1, "partly": 1, "stored": 0}[which]
    assert full.stdout.count("\n  ok ") == {"solutions": len(a.variables()), "release": 0,
                                             "partly": len(a.variables()) - 2,
                                             "stored": len(a.variables())}[which]
    assert "did not finish normally" not in full.stdout  # no cell failed (%store ran)


@pytest.mark.parametrize("command", ["full", "student"])
def test_a_fifo_or_a_link_to_a_device_is_refused_at_once(venv, tmp_path, command):
    argv = ([sys.executable, "-m", "eulertop", "check"] if command == "full" else
            [str(venv / "bin" / "eulertop-check")])
    fifo = tmp_path / "f.ipynb"
    os.mkfifo(fifo)
    (tmp_path / "zero.ipynb").symlink_to("/dev/zero")
    for path, kind in ((fifo, "a named pipe (FIFO)"), (tmp_path / "zero.ipynb",
                                                        "a symbolic link")):
        run = subprocess.run([*argv, str(path)], capture_output=True, text=True, timeout=60,
                             cwd=ROOT)
        assert run.returncode == 2 and run.stdout == ""
        assert run.stderr.strip().endswith(f"{path.name} is {kind}, not a file")
        assert len(run.stderr.strip().splitlines()) == 1


def test_max_size_is_one_limit_stated_alike(venv, generated_assignment):
    full = subprocess.run([sys.executable, "-m", "eulertop", "check", "--help"],
                          capture_output=True, text=True, timeout=60, cwd=ROOT).stdout
    grade = subprocess.run([sys.executable, "-m", "eulertop", "grade", "--help"],
                           capture_output=True, text=True, timeout=60, cwd=ROOT).stdout
    student = subprocess.run([str(venv / "bin" / "eulertop-check"), "--help"],
                             capture_output=True, text=True, timeout=60).stdout
    stated = " ".join(MAX_SIZE_HELP.split())
    assert "default 20 MiB" in stated
    for text in (full, grade, student):
        assert stated in " ".join(text.split())
    path = generated_assignment.release()
    run = subprocess.run([str(venv / "bin" / "eulertop-check"), "--max-size", "1K", str(path)],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 2 and "over the 1 KiB limit (--max-size)" in run.stderr


# --- beside the full package -----------------------------------------------------------------

FULL_SOURCES = ("solver", "problems", "grader", "eulertop", "eulertop_base", "pyproject.toml",
                "README.md")
"""What the full package is built from."""


@pytest.fixture(scope="module")
def full_wheel(tmp_path_factory) -> Path:
    """The full package's wheel, built from a copy of its sources (the working tree's own
    build folder may hold files of an earlier layout, which a wheel would take)."""
    source = tmp_path_factory.mktemp("full-source")
    for name in FULL_SOURCES:
        if (ROOT / name).is_dir():
            shutil.copytree(ROOT / name, source / name,
                            ignore=shutil.ignore_patterns("__pycache__"))
        else:
            shutil.copy2(ROOT / name, source / name)
    out = tmp_path_factory.mktemp("full-wheel")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", str(out),
                    str(source)], check=True, capture_output=True, timeout=300)
    (found,) = out.glob("eulertop-*.whl")
    return found


def _in(venv: Path, *argv: str, **kw) -> subprocess.CompletedProcess:
    """``argv`` run with the venv's own executables (``python``, ``eulertop``, ``pip`` …)."""
    return subprocess.run([str(venv / "bin" / argv[0]), *argv[1:]], capture_output=True,
                          text=True, timeout=600, cwd=venv, **kw)


def _files_of_each(venv: Path) -> dict[str, set[str]]:
    code = ("import json, importlib.metadata as m\n"
            "print(json.dumps({d: [str(f) for f in m.distribution(d).files]"
            " for d in ('eulertop', 'eulertop-check')}))")
    return {d: set(files) for d, files in json.loads(_in(venv, "python", "-c", code).stdout)
            .items()}


def _both_check(venv: Path, path: Path, commands: tuple[str, ...]) -> list[list[str]]:
    """What each command says of ``path`` (each must exit 0)."""
    said = []
    for command in commands:
        argv = ("eulertop", "check") if command == "eulertop" else (command,)
        run = _in(venv, *argv, str(path))
        assert run.returncode == 0, (command, run.stdout, run.stderr)
        said.append(_verdicts(run.stdout))
    return said


def _grader_file(venv: Path) -> str:
    run = _in(venv, "python", "-c", "import eulertop_check, grader.check\n"
                                    "print(grader.check.__file__)")
    assert run.returncode == 0, run.stderr
    return run.stdout.strip()


def test_both_distributions_in_one_venv_keep_each_other_whole(full_wheel, wheel,
                                                               generated_assignment,
                                                               tmp_path_factory):
    """The full package and the student's in one venv: no file installed by both; both
    commands work and agree, the full package's own ``grader`` used; either one removed, the
    other still works; and beside an editable install of the full package, that one's."""
    folder = tmp_path_factory.mktemp("both-venv")
    subprocess.run([sys.executable, "-m", "venv", str(folder)], check=True, timeout=120)
    path = generated_assignment.solutions()
    for wheel_file in (full_wheel, wheel):
        installed = _in(folder, "python", "-m", "pip", "install", *QUICK, str(wheel_file))
        assert installed.returncode == 0
    files = _files_of_each(folder)
    assert files["eulertop"] & files["eulertop-check"] == set()
    full, student = _both_check(folder, path, ("eulertop", "eulertop-check"))
    assert full == student
    assert Path(_grader_file(folder)).parts[-3:] == ("site-packages", "grader", "check.py")

    assert _in(folder, "python", "-m", "pip", "uninstall", "-y", "eulertop-check").returncode == 0
    assert _both_check(folder, path, ("eulertop",)) == [full]
    assert _in(folder, "python", "-m", "pip", "install", *QUICK, str(wheel)).returncode == 0
    assert _in(folder, "python", "-m", "pip", "uninstall", "-y", "eulertop").returncode == 0
    assert _both_check(folder, path, ("eulertop-check",)) == [full]
    assert "_shared" in Path(_grader_file(folder)).parts

    editable = _in(folder, "python", "-m", "pip", "install", "-q", "--no-deps", "-e", str(ROOT))
    assert editable.returncode == 0, editable.stderr
    assert _both_check(folder, path, ("eulertop", "eulertop-check")) == [full, full]
    assert Path(_grader_file(folder)) == ROOT / "grader" / "check.py"


# --- in a live kernel of the student's venv ---------------------------------------------------


class Kernel:
    """A real ipykernel of the student's venv, started by jupyter_client."""

    def __init__(self, venv: Path, cwd: Path, env: dict, connection_file: Path) -> None:
        from jupyter_client.kernelspec import KernelSpec
        from jupyter_client.manager import KernelManager

        self.km = KernelManager(connection_file=str(connection_file))
        self.km._kernel_spec = KernelSpec(
            argv=[str(venv / "bin" / "python"), "-m", "ipykernel_launcher", "-f",
                  "{connection_file}"], language="python", display_name="student")
        self.km.start_kernel(cwd=str(cwd), env={**_plain_env(), **env})
        self.kc = self.km.client()
        self.kc.start_channels()
        self.kc.wait_for_ready(timeout=120)

    def run(self, code: str) -> dict:
        """What a cell shows: its printed text, its HTML, its error's traceback lines."""
        shown = {"text": "", "html": "", "error": []}

        def hook(msg: dict) -> None:
            kind, content = msg["msg_type"], msg["content"]
            if kind == "stream":
                shown["text"] += content["text"]
            elif kind in ("display_data", "execute_result"):
                shown["html"] += content["data"].get("text/html", "")
            elif kind == "error":
                shown["error"] = content["traceback"]

        self.kc.execute_interactive(code, output_hook=hook, timeout=240)
        return shown

    def stop(self) -> None:
        self.kc.stop_channels()
        self.km.shutdown_kernel(now=True)


def _plain_env() -> dict:
    keep = ("PATH", "HOME", "LANG", "TMPDIR", "PIP_FIND_LINKS")
    return {k: v for k, v in os.environ.items() if k in keep}


@pytest.fixture
def saved(generated_assignment, tmp_path) -> Path:
    """alice's notebook as saved: her first question answered (the solutions' line), the rest
    None."""
    a = generated_assignment
    nb = a.notebook("release")
    solved = a.notebook("solutions")
    for cell, answered in zip(nb["cells"], solved["cells"], strict=True):
        if cell["metadata"].get("eulertop", {}).get("role") == "answer" and \
                cell["metadata"]["eulertop"]["question"] == 1:
            cell["source"] = answered["source"]
    path = tmp_path / "work" / "alice.ipynb"
    path.parent.mkdir()
    path.write_text(json.dumps(nb), encoding="utf-8")
    return path


def _all_answers(a) -> str:
    """The solutions' parameter and answer cells: every answer set, live."""
    nb = a.notebook("solutions")
    return "\n".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "code")


def test_check_in_jupyterlab_reads_the_live_answers(venv, generated_assignment, saved, tmp_path):
    a = generated_assignment
    kernel = Kernel(venv, saved.parent, {"JPY_SESSION_NAME": str(saved)},
                    tmp_path / "kernel-lab.json")
    try:
        first = kernel.run("import eulertop_check\neulertop_check.check()")
        assert "<table>" in first["html"] and "missing" in first["html"]
        kernel.run(_all_answers(a))
        shown = kernel.run("r = eulertop_check.check()\nprint(r.all_well_formed)\nprint(r)\nr")
        n = len(a.variables())
        assert shown["text"].startswith("True\nChecked the answers in this kernel against "
                                        "alice.ipynb (found by the Jupyter server "
                                        "(JPY_SESSION_NAME)):")
        assert f"{n} of {n} answers present and well formed." in shown["text"]
        assert shown["html"].count("<tr>") == n + 1  # and its header
        kernel.run(f"{a.variables()[0]} = 'fast'")
        bad = kernel.run("print(eulertop_check.check())")["text"]
        assert f"malformed {a.variables()[0]}" in " ".join(bad.split())
    finally:
        kernel.stop()


def test_check_run_names_what_the_saved_notebook_gives_otherwise(venv, generated_assignment,
                                                                  saved, tmp_path):
    a = generated_assignment
    kernel = Kernel(venv, saved.parent, {"JPY_SESSION_NAME": saved.name},
                    tmp_path / "kernel-run.json")
    try:
        kernel.run(_all_answers(a))
        shown = kernel.run("import eulertop_check\nr = eulertop_check.check(run=True)\n"
                           "print(r.all_well_formed)\nprint(r)")["text"]
    finally:
        kernel.stop()
    q1 = [v for v in a.variables() if v.startswith("q1_")]
    later = [v for v in a.variables() if not v.startswith("q1_")]
    assert shown.startswith("False\n")
    for variable in later:
        assert f"your saved notebook gives {variable} = None, this kernel " in shown
    assert shown.count("save it, then Restart and Run All") == len(later)
    assert not any(f"gives {v} =" in shown for v in q1)


def test_check_in_vs_code_finds_the_notebook_it_names(venv, generated_assignment, saved,
                                                     tmp_path):
    kernel = Kernel(venv, saved.parent, {}, tmp_path / "kernel-vsc.json")
    try:
        shown = kernel.run(f"__vsc_ipynb_file__ = {str(saved)!r}\nimport eulertop_check\n"
                           "print(eulertop_check.check())")["text"]
    finally:
        kernel.stop()
    assert shown.startswith("Checked the answers in this kernel against alice.ipynb (found by "
                            "VS Code):")


COLAB_MESSAGE = """\
import json, os

ASKED = []


def blocking_request(request_type, request="", timeout_sec=5, parent=None):
    ASKED.append(request_type)
    if request_type != "get_ipynb":
        raise ValueError(f"this stand-in answers get_ipynb only, not {request_type!r}")
    with open(os.environ["COLAB_HOLDS"], encoding="utf-8") as f:
        return {"ipynb": json.load(f)}
"""
"""A stand-in of Colab's ``google.colab._message``: ``blocking_request("get_ipynb")`` answers
with the notebook Colab holds (here a file that is not a notebook's, outside the kernel's
folder), as Colab's does; every request is recorded."""


def test_check_on_colab_reads_the_notebook_colab_holds(venv, generated_assignment, saved,
                                                      tmp_path):
    """On Colab there is no notebook file: the one Colab holds is asked for, and checked as
    it is saved (``run=True``); nothing but ``get_ipynb`` is asked (no save forced)."""
    a = generated_assignment
    colab = tmp_path / "colab" / "google" / "colab"
    colab.mkdir(parents=True)
    (colab / "__init__.py").write_text("", encoding="utf-8")
    (colab / "_message.py").write_text(COLAB_MESSAGE, encoding="utf-8")
    held = tmp_path / "held-by-colab.json"
    held.write_text(saved.read_text(encoding="utf-8"), encoding="utf-8")
    content, runtime = tmp_path / "content", tmp_path / "runtime"
    content.mkdir()
    runtime.mkdir()
    kernel = Kernel(venv, content, {"PYTHONPATH": str(tmp_path / "colab"),
                                    "COLAB_HOLDS": str(held),
                                    "JUPYTER_RUNTIME_DIR": str(runtime)},
                    tmp_path / "kernel-colab.json")
    try:
        kernel.run(_all_answers(a))
        shown = kernel.run("import eulertop_check\nprint(eulertop_check.check())\n"
                           "print(eulertop_check.check(run=True))\n"
                           "from google.colab import _message\nprint(_message.ASKED)")["text"]
    finally:
        kernel.stop()
    now, saved_run = shown.split("Checked the answers")[1:]
    n = len(a.variables())
    assert now.startswith(" in this kernel against alice.ipynb (found by Colab):")
    assert f"{n} of {n} answers present and well formed." in now
    later = [v for v in a.variables() if not v.startswith("q1_")]
    for variable in later:
        assert f"your saved notebook gives {variable} = None, this kernel " in saved_run
    assert saved_run.count("save it, then Restart and Run All") == len(later)
    assert shown.rstrip().endswith("['get_ipynb', 'get_ipynb']")
    assert list(content.iterdir()) == []  # nothing written where it runs


def test_check_finds_the_notebook_from_the_servers_sessions(venv, generated_assignment,
                                                            saved, tmp_path):
    """A Jupyter server of the test's own, on the loopback: its runtime file names it, and its
    api/sessions names the notebook of the kernel whose connection file is kernel-<id>.json."""
    asked = []

    class Sessions(BaseHTTPRequestHandler):
        def do_GET(self) -> None:
            asked.append((self.path, self.headers.get("Authorization")))
            body = json.dumps([{"path": "work/other.ipynb", "kernel": {"id": "another"}},
                               {"path": "work/alice.ipynb", "kernel": {"id": "k-7f3"}}])
            self.send_response(200)
            self.end_headers()
            self.wfile.write(body.encode())

        def log_message(self, *args) -> None:
            pass

    server = HTTPServer(("127.0.0.1", 0), Sessions)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    runtime = tmp_path / "runtime"
    runtime.mkdir()
    (runtime / "jpserver-1.json").write_text(json.dumps({
        "url": f"http://127.0.0.1:{server.server_port}/", "token": "t0k",
        "root_dir": str(saved.parent.parent)}))
    kernel = Kernel(venv, saved.parent, {"JUPYTER_RUNTIME_DIR": str(runtime)},
                    tmp_path / "kernel-k-7f3.json")
    try:
        shown = kernel.run("import eulertop_check\nprint(eulertop_check.check())")["text"]
    finally:
        kernel.stop()
        server.shutdown()
    assert shown.startswith("Checked the answers in this kernel against alice.ipynb (found by "
                            "the Jupyter server's sessions):")
    assert asked == [("/api/sessions", "token t0k")]


def test_without_a_front_ends_word_it_says_what_to_do_in_one_line(venv, tmp_path):
    kernel = Kernel(venv, tmp_path, {}, tmp_path / "kernel-plain.json")
    try:
        shown = kernel.run("import eulertop_check\neulertop_check.check()")
    finally:
        kernel.stop()
    assert shown["error"] == ["eulertop_check: could not tell which notebook this kernel runs "
                              "(no Jupyter server, VS Code or Colab said): name it, "
                              "eulertop_check.check(\"ada.ipynb\")"]
