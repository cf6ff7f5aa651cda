"""One house (issue 24): every import points down a floor, or sideways without a circle.

The imports are read statically (``ast``) from every module of the four top-level packages,
function-level imports included — a lazy import is still a dependency — and those under
``if TYPE_CHECKING:`` left out. The floors are data (:data:`FLOORS`): the package or module,
its floor. A module takes its own entry; a module without one takes the floor of the package
around it only where that package is listed as a whole room (:data:`WHOLE_ROOMS`: every module
in it shares its floor). ``grader`` is not one: each of its loose modules is a stage with a
floor of its own, so a new one must be given its floor. Checked:

* every module has a floor (a new module must be placed; a made-up one is refused);
* no module imports one on a higher floor;
* no circle between modules (strongly connected components of one);
* no circle between rooms: the top-level packages, and grader's sub-packages among themselves.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("eulertop_base", "solver", "problems", "grader", "eulertop", "eulertop_check")

FLOORS = {
    # what both distributions stand on (the student package, issue 33, has no solver)
    "eulertop_base": -1,
    # the lecture's physics, then problems built on it
    "solver": 0,
    "problems": 10,
    # grader, floor 0: records and pure helpers
    "grader.limits": 20, "grader.plain_text": 20, "grader.statement_html": 20,
    "grader.results": 20, "grader.submissions": 20, "grader.submission_file": 20,
    "grader.notebook_load": 20, "grader.extract": 20, "grader.notebook_metadata": 20,
    "grader.written": 20,
    # 1–2: one disposable world; one kernel
    "grader.sandbox": 21,
    "grader.kernels": 22,
    # 3: the stages of one submission
    "grader.execute": 23, "grader.compare": 23,
    # 4: the unit, and what it is graded against, and where its records go
    "grader.assignment": 24, "grader.graded_folder": 24, "grader.grade_one": 24,
    "grader.overrides": 24, "grader.audit": 24, "grader.follow_through": 24,
    "grader.key_edit": 24, "grader.transaction": 24, "grader.late": 24, "grader.reviews": 24,
    "grader.run_file": 24,
    # 5: views of records, and file formats
    "grader.gradebook": 25, "grader.progress": 25, "grader.lms": 25, "grader.report": 25,
    "grader.table_rows": 25,
    # 6: where grade_one runs; where submissions come from
    "grader.executors": 26, "grader.discover": 26, "grader.publish": 26,
    # 7: the class run
    "grader.pipeline": 27, "grader.rescore": 27, "grader.review": 27,
    # 8: front ends
    "grader": 28, "grader.cli": 28, "grader.amend": 28, "grader.check": 28,
    "grader.doctor": 28, "grader.selftest_run": 28, "grader.report.cli": 28,
    "grader.lms.export": 28, "grader.hosted": 28,
    # the student package's front ends: check() in a notebook, eulertop-check (issue 33)
    "eulertop_check": 28,
    # the review desk (issue 31): a web app above grader/, which nothing in grader/ imports
    "eulertop.review_app": 30,
    # the console script and what composes the rooms
    "eulertop": 40,
}

SUBPACKAGES = ("grader.sandbox", "grader.kernels", "grader.executors", "grader.lms",
               "grader.report", "grader.hosted")

WHOLE_ROOMS = ("eulertop_base", "solver", "problems", "eulertop", "eulertop_check",
               "eulertop.review_app", *SUBPACKAGES)
"""Packages whose modules take the package's floor unless listed themselves (``grader.lms``'s
formats are floor 5, its ``export`` front end is listed at 8). ``grader`` is not one."""


def module_files() -> dict[str, Path]:
    found = {}
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            name = ".".join(path.relative_to(ROOT).with_suffix("").parts)
            found[name.removesuffix(".__init__")] = path
    return found


MODULES = module_files()


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or \
        (isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING")


def imports_of(name: str, path: Path) -> set[str]:
    """The project's modules that module ``name`` imports (at any depth in its code)."""
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    named: set[str] = set()

    def visit(node: ast.AST) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.orelse:
                visit(child)
            return
        if isinstance(node, ast.Import):
            named.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                parts = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*parts, *([node.module] if node.module else [])])
            for alias in node.names:  # `from grader.sandbox import world` names a module
                full = f"{base}.{alias.name}"
                named.add(full if full in MODULES else base)
        for child in ast.iter_child_nodes(node):
            visit(child)

    visit(ast.parse(path.read_text(encoding="utf-8")))
    out = set()
    for target in named:
        while target and target not in MODULES:
            target = target.rpartition(".")[0]
        if target and target != name:
            out.add(target)
    return out


GRAPH = {name: imports_of(name, path) for name, path in MODULES.items()}


def floor(name: str) -> int:
    """Module ``name``'s floor: its own entry, else that of the innermost whole room holding
    it; KeyError when it has neither (it must be placed)."""
    if name in FLOORS:
        return FLOORS[name]
    parts = name.split(".")
    for i in range(len(parts) - 1, 0, -1):
        room = ".".join(parts[:i])
        if room in WHOLE_ROOMS:
            return FLOORS[room]
    raise KeyError(name)


def unplaced(names) -> list[str]:
    """The modules of ``names`` that have no floor."""
    missing = []
    for name in names:
        try:
            floor(name)
        except KeyError:
            missing.append(name)
    return missing


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found = []
    counter = 0
    for root in graph:
        if root in index:
            continue
        work = [(root, iter(sorted(graph.get(root, ()))))]
        index[root] = low[root] = counter
        counter += 1
        stack.append(root)
        on.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = counter
                    counter += 1
                    stack.append(child)
                    on.add(child)
                    work.append((child, iter(sorted(graph.get(child, ())))))
                elif child in on:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                component = []
                while True:
                    top = stack.pop()
                    on.discard(top)
                    component.append(top)
                    if top == node:
                        break
                if len(component) > 1:
                    found.append(sorted(component))
    return found


def rooms(level: str) -> dict[str, set[str]]:
    """The import graph between rooms: ``top`` — the top-level packages; ``sub`` — grader's
    sub-packages among themselves (its loose modules belong to no sub-package)."""
    def room(name: str) -> str | None:
        if level == "top":
            return name.split(".")[0]
        return next((s for s in SUBPACKAGES if name == s or name.startswith(s + ".")), None)

    graph: dict[str, set[str]] = {}
    for a, targets in GRAPH.items():
        for b in targets:
            ra, rb = room(a), room(b)
            if ra and rb and ra != rb:
                graph.setdefault(ra, set()).add(rb)
    return graph


def test_the_walk_sees_the_project():
    """The reader finds what is there: a known downward edge, and a lazy import."""
    assert "grader.pipeline" in GRAPH["grader.cli"]  # imported inside run_grade
    assert "grader.execute" in GRAPH["grader.run_file"]  # imported inside run_one
    assert {"solver", "problems", "grader", "eulertop"} <= set(MODULES)
    assert len(MODULES) > 100


def test_every_module_has_a_floor():
    assert unplaced(MODULES) == []


def test_a_new_module_must_be_placed():
    """Control of the test above: a made-up loose grader module has no floor (``"grader"``
    names the package's own ``__init__``, not a room), nor has a new top-level package; a new
    module inside a whole room takes the room's floor."""
    made_up = ["grader.new_stage", "grader.new_room.part", "newpackage.module",
               "grader.report.new_view", "problems.templates.new_family", "solver.new_model"]
    assert unplaced(made_up) == ["grader.new_stage", "grader.new_room.part",
                                 "newpackage.module"]
    assert floor("grader.report.new_view") == FLOORS["grader.report"]
    assert all(room in FLOORS for room in WHOLE_ROOMS)


def test_no_module_imports_a_higher_floor():
    upward = sorted(f"{a} (floor {floor(a)}) imports {b} (floor {floor(b)})"
                    for a, targets in GRAPH.items() for b in targets if floor(a) < floor(b))
    assert upward == []


def test_no_circle_between_modules():
    assert circles(GRAPH) == []


@pytest.mark.parametrize("level", ["top", "sub"])
def test_no_circle_between_rooms(level):
    assert circles(rooms(level)) == []


def test_the_circle_finder_finds_circles():
    """Control of the tests above: the finder reports a circle when there is one."""
    assert circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert circles({"a": {"b"}, "b": set()}) == []


def test_the_review_desk_is_a_room_above_grader():
    """Issue 31: the web app's modules sit on its own floor, above every grader module, and
    nothing in grader/ imports them."""
    desk = [name for name in MODULES if name.startswith("eulertop.review_app")]
    assert len(desk) > 3 and {floor(name) for name in desk} == {FLOORS["eulertop.review_app"]}
    assert FLOORS["eulertop.review_app"] > max(v for k, v in FLOORS.items()
                                               if k.startswith("grader"))
    assert not [(a, b) for a, targets in GRAPH.items() if a.startswith("grader")
                for b in targets if b.startswith("eulertop.review_app")]


def test_every_grader_module_names_its_floor_in_its_docstring():
    """A reader of any grader module learns its floor's job from its docstring
    ("Floor N of grader/ (…)"), and the number agrees with :data:`FLOORS`."""
    import re

    wrong = []
    for name, path in MODULES.items():
        if not name.startswith("grader"):
            continue
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"))) or ""
        said = re.search(r"Floor (\d) of grader/ \(", doc)
        if said is None or int(said.group(1)) != floor(name) - FLOORS["grader.limits"]:
            wrong.append(name)
    assert wrong == []
