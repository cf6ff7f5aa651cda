"""``eulertop package HW --for gradescope|prairielearn --out PATH``: what each platform takes.

Gradescope (:func:`gradescope_zip`)
    A zip with, at its root (Gradescope's "Autograder Specifications"): ``setup.sh``, which
    installs eulertop from the wheel in the zip into ``/opt/eulertop`` (its dependencies from
    the package index, pinned to the versions this eulertop runs with: ``constraints.txt``),
    ``run_autograder``, the assignment's manifest and key and its own families' files
    (``assignment/``, nothing else of HW), and :data:`grader.hosted.grading.CONFIG`.

PrairieLearn (:func:`prairielearn_question`)
    ``OUT/questions/<name>/``: a question for a course repository — ``info.json`` (external
    grading, a JupyterLab workspace), ``question.html``, ``server.py`` (picks a variant from
    PrairieLearn's variant seed), ``variants/`` (the notebooks the workspace offers, made by
    eulertop's generator from HW's seed and problems) and ``tests/`` (the grader's entrypoint,
    the variants' key, the settings; PrairieLearn copies it to ``/grade/tests``, never to
    students). ``OUT/grader-image/``: a ``Dockerfile`` that builds the grading image from the
    wheel. ``OUT/solutions/<name>/``: each variant's solutions, for the instructor only.

Families of the instructor's own (a file, or an installed package's module) go into the
package (``assignment/families/<name>/``, :func:`ship_families`) and its manifest names those
copies, so that the platform grades follow-through credit exactly as ``eulertop grade`` does.
Each is loaded from its copy, in a process of its own, before the package is written: one that
cannot be is a :class:`PackageError`, as is (for Gradescope, which carries HW's key) a family
file edited since ``eulertop generate``.

Floor 8 of grader/ (front ends; grader/API.md).
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import stat
import subprocess
import sys
import tempfile
import zipfile
from collections.abc import Iterable
from importlib import metadata
from pathlib import Path

from grader.assignment import Assignment, UsageError, load_assignment
from grader.hosted.grading import CONFIG, MODES, limits_dict
from grader.limits import Limits

PLATFORMS = ("gradescope", "prairielearn")
VENV = "/opt/eulertop"
"""Where the platforms' images get eulertop: readable and runnable by every user (the kernel
runs this Python as an unprivileged user)."""

SETUP_SH = r"""#!/usr/bin/env bash
# Gradescope runs this once, as root, when it builds the autograder's image.
# It installs eulertop from the wheel in this zip into __VENV__ (readable by every user: the
# student's notebook runs its Python as an unprivileged user), its dependencies pinned.
set -euo pipefail
cd "$(dirname "$0")"
PY=""
for candidate in python3.13 python3.12 python3.11 python3; do
  if command -v "$candidate" >/dev/null &&
     "$candidate" -c 'import sys; sys.exit(sys.version_info < (3, 11))'; then
    PY="$(command -v "$candidate")"; break
  fi
done
export DEBIAN_FRONTEND=noninteractive
if [ -z "$PY" ]; then
  apt-get update && apt-get install -y python3.11 python3.11-venv
  PY="$(command -v python3.11)"
fi
if ! "$PY" -m venv __VENV__; then
  apt-get update && apt-get install -y "$(basename "$PY")-venv"
  "$PY" -m venv __VENV__
fi
__VENV__/bin/python -m pip install --constraint constraints.txt ./__WHEEL__
chmod -R go+rX __VENV__
"""

RUN_AUTOGRADER = """#!/usr/bin/env bash
# Gradescope runs this, as root, for every submission: results in /autograder/results.
exec __VENV__/bin/python -m grader.hosted.gradescope "$@"
"""

PL_RUN = """#!/usr/bin/env bash
# PrairieLearn's external grader runs this (info.json's entrypoint) in the grading image.
exec __VENV__/bin/python -m grader.hosted.prairielearn "$@"
"""

DOCKERFILE = """# The grading image of the eulertop question: build it, push it to Docker Hub,
# and name it in the question's info.json ("externalGradingOptions": {"image": ...}).
FROM python:3.12-slim
COPY __WHEEL__ constraints.txt /tmp/eulertop/
RUN python -m venv __VENV__ \\
 && __VENV__/bin/python -m pip install --no-cache-dir \\
      --constraint /tmp/eulertop/constraints.txt /tmp/eulertop/__WHEEL__ \\
 && chmod -R go+rX __VENV__ && rm -rf /tmp/eulertop
"""


class PackageError(UsageError):
    """The package cannot be built (bad option, no wheel); nothing is left half written."""


# --------------------------------------------------------------------------------------------
# the wheel and the pins


def project_root() -> Path | None:
    """The source tree eulertop runs from (holding ``pyproject.toml``), if any."""
    root = Path(__file__).resolve().parents[2]
    return root if (root / "pyproject.toml").is_file() else None


SOURCES = ("pyproject.toml", "README.md", "eulertop", "grader", "problems", "solver")
"""What of the source tree goes into the wheel (``pyproject.toml``'s packages)."""


def build_wheel(dest: Path) -> Path:
    """``pip wheel --no-deps`` of a copy of the source tree into ``dest``; the wheel's path.

    Built from a copy in ``dest`` so that nothing is written into the source tree (and no
    stale ``build/`` folder there ends up in the wheel)."""
    root = project_root()
    if root is None:
        raise PackageError("eulertop is not running from its source tree, so no wheel can be "
                           "built here: pass --wheel FILE (a wheel of this eulertop version)")
    copy = dest / "source"
    for name in SOURCES:
        if (root / name).is_dir():
            shutil.copytree(root / name, copy / name,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
        elif (root / name).is_file():
            copy.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(root / name, copy / name)
    base = [sys.executable, "-m", "pip", "wheel", "--no-deps", "--quiet", str(copy), "-w",
            str(dest)]
    done = subprocess.run([*base, "--no-build-isolation"], capture_output=True, text=True)
    if done.returncode != 0:
        done = subprocess.run(base, capture_output=True, text=True)
    wheels = sorted(dest.glob("eulertop-*.whl"))
    if done.returncode != 0 or not wheels:
        last = (done.stderr.strip().splitlines() or ["no message"])[-1]
        raise PackageError(f"could not build eulertop's wheel from {root}: {last}; pass "
                           "--wheel FILE")
    return wheels[-1]


def _name(requirement: str) -> str:
    return re.split(r"[\s\[<>=!~;(]", requirement.strip(), maxsplit=1)[0]


def pinned_requirements(top: str = "eulertop") -> list[str]:
    """``name==version`` of every installed distribution ``top`` needs (recursively, extras
    and environment-marked requirements that do not apply here left out), sorted."""
    from packaging.requirements import Requirement

    pins, todo, seen = {}, [top], set()
    while todo:
        name = todo.pop()
        key = name.lower().replace("_", "-")
        if key in seen:
            continue
        seen.add(key)
        try:
            dist = metadata.distribution(name)
        except metadata.PackageNotFoundError:
            continue
        if name != top:
            pins[dist.metadata["Name"]] = dist.version
        for text in dist.requires or ():
            req = Requirement(text)
            if req.marker is None or req.marker.evaluate({"extra": ""}):
                todo.append(req.name)
    return [f"{n}=={v}" for n, v in sorted(pins.items(), key=lambda p: p[0].lower())]


# --------------------------------------------------------------------------------------------
# Gradescope


def _text(template: str, **values: str) -> str:
    for k, v in values.items():
        template = template.replace(f"__{k}__", v)
    return template


def _add(zf: zipfile.ZipFile, name: str, data: bytes | str, executable: bool = False) -> None:
    info = zipfile.ZipInfo(name, date_time=(2020, 1, 1, 0, 0, 0))
    info.external_attr = ((0o755 if executable else 0o644) | stat.S_IFREG) << 16
    info.compress_type = zipfile.ZIP_DEFLATED
    zf.writestr(info, data.encode() if isinstance(data, str) else data)


def settings(args: argparse.Namespace, limits: Limits, **more: object) -> dict:
    """The package's :data:`CONFIG`."""
    return {"sandbox": args.sandbox, "kernel_user": args.kernel_user,
            "limits": limits_dict(limits), **more}


def gradescope_zip(a: Assignment, out: Path, wheel: Path, config: dict) -> Path:
    """Write Gradescope's autograder zip ``out`` (module docstring); its path."""
    from grader.follow_through import unchanged_families

    values = {"VENV": VENV, "WHEEL": wheel.name}
    try:
        unchanged_families(a)  # the zip carries HW's key: the families must be the key's
    except UsageError as e:
        raise PackageError(str(e)) from None
    out.parent.mkdir(parents=True, exist_ok=True)
    tmp = out.with_name(f".{out.name}.part")
    with tempfile.TemporaryDirectory(prefix="eulertop-package-") as staging, \
            zipfile.ZipFile(tmp, "w") as zf:
        assignment = staged_assignment(a.manifest, a.folder, a.folder / "key.json",
                                       Path(staging) / "assignment")
        _add(zf, "setup.sh", _text(SETUP_SH, **values), executable=True)
        _add(zf, "run_autograder", _text(RUN_AUTOGRADER, **values), executable=True)
        _add(zf, wheel.name, wheel.read_bytes())
        _add(zf, "constraints.txt", "\n".join(pinned_requirements()) + "\n")
        _add(zf, CONFIG, json.dumps(config, indent=1) + "\n")
        for path in sorted(p for p in assignment.rglob("*") if p.is_file()):
            _add(zf, f"assignment/{path.relative_to(assignment).as_posix()}", path.read_bytes())
    tmp.replace(out)
    return out


# --------------------------------------------------------------------------------------------
# the assignment's own families

FAMILY_FILES = "families"
"""Where a package's assignment folder holds the families of the instructor's own."""


def staged_assignment(manifest: dict, source: Path, key: Path, dest: Path) -> Path:
    """``dest``: the assignment as a package carries it — ``manifest`` naming the copies of its
    own families (:func:`ship_families`; their files relative to ``source``), the key file
    ``key`` — checked as the platform will load it (:func:`check_families`)."""
    from problems.generate import json_text

    dest.mkdir(parents=True)
    shipped = ship_families(manifest, source, dest)
    (dest / "assignment.json").write_text(json_text(shipped), encoding="utf-8")
    shutil.copyfile(key, dest / "key.json")
    check_families(dest)
    return dest


def ship_families(manifest: dict, source: Path, dest: Path) -> dict:
    """Copy each family ``manifest`` records from outside the package — a file (relative to
    ``source``), a package's folder, or an installed package's module — into
    ``dest/families/<name>/``; ``manifest`` naming those copies (and the SHA-256 it
    recorded)."""
    record = {}
    for name, where in manifest.get("families", {}).items():
        path = _family_source(name, where, source)
        target = dest / FAMILY_FILES / name
        if path.name == "__init__.py":  # a package: its folder
            shutil.copytree(path.parent, target / path.parent.name,
                            ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
            copy = target / path.parent.name / "__init__.py"
        else:
            target.mkdir(parents=True)
            copy = target / path.name
            shutil.copyfile(path, copy)
        record[name] = {"file": copy.relative_to(dest).as_posix(),
                        "sha256": where.get("sha256")}
    return {**manifest, "families": record} if record else dict(manifest)


def _family_source(name: str, where: dict, source: Path) -> Path:
    """The file a recorded family comes from (an installed package's: its module's)."""
    from problems.family import FamilyError
    from problems.family_files import entry_point_families

    if "file" in where:
        path = Path(source) / where["file"]
        if not path.is_file():
            raise PackageError(f"{path}: family {name!r}'s file is gone; the package must carry "
                               "it (put it back where 'eulertop generate' found it)")
        return path
    try:
        installed = {f.name: f for f in entry_point_families()}
    except FamilyError as e:
        raise PackageError(str(e)) from None
    if name not in installed or installed[name].path is None:
        raise PackageError(f"family {name!r} ({where.get('origin')}) is not installed here, "
                           "so the package cannot carry it")
    return installed[name].path


def check_families(folder: Path) -> None:
    """Load each own family of the assignment ``folder`` as the platform's grader will (its
    follow-through worker, a process of its own); :class:`PackageError` naming the first
    that cannot be."""
    from grader.follow_through import FamilyUnavailable, FollowThrough

    try:
        follow = FollowThrough.of(load_assignment(folder))
    except UsageError as e:  # a copy that is not the file the key was computed with
        raise PackageError(str(e)) from None
    if follow is None:
        return  # no follow-through credit: the families are never loaded there
    try:
        follow.load_families()
    except FamilyUnavailable as e:
        raise PackageError(f"family {e.family!r} cannot be loaded as the package carries it "
                           f"(in {FAMILY_FILES}/{e.family}/): {e.cause}") from None
    finally:
        follow.close()


# --------------------------------------------------------------------------------------------
# PrairieLearn

NOTEBOOK = "homework.ipynb"
"""The notebook's name in the student's workspace (``gradedFiles``)."""

WORKSPACE_IMAGE = "prairielearn/workspace-jupyterlab-python"
WORKSPACE_HOME = "/home/jovyan"

SERVER_PY = '''"""PrairieLearn question code (generated by eulertop package --for prairielearn).

generate(): PrairieLearn's variant seed picks one of the variants in variants/ (each made by
eulertop's generator); the workspace offers that variant's notebook, and the grader reads
params["eulertop_variant"] to grade against that variant's key.
"""

import zlib

VARIANTS = __VARIANTS__
NOTEBOOK = __NOTEBOOK__


def variant_of(seed):
    text = str(seed)
    number = int(text) if text.isdigit() else zlib.crc32(text.encode())
    return VARIANTS[number % len(VARIANTS)]


def generate(data):
    variant = variant_of(data["variant_seed"])
    data["params"]["eulertop_variant"] = variant
    data["params"]["_workspace_files"] = [
        {"name": NOTEBOOK, "questionFile": "variants/" + variant + ".ipynb"},
    ]
'''

QUESTION_HTML = """<pl-question-panel>
  <p>__TITLE__ (variant {{params.eulertop_variant}}): open the workspace, answer every question
  in <code>__NOTEBOOK__</code>, run it from the top, save it, and submit.</p>
  <pl-workspace></pl-workspace>
</pl-question-panel>

<pl-submission-panel>
  <pl-external-grader-results></pl-external-grader-results>
  <pl-file-preview></pl-file-preview>
</pl-submission-panel>
"""


def variant_ids(count: int) -> list[str]:
    width = max(3, len(str(count - 1)))
    return [f"v{i:0{width}d}" for i in range(count)]


def pool_assignment(a: Assignment, count: int, dest: Path) -> Path:
    """``count`` variants of ``a`` generated into ``dest``: its seed, and its questions as it
    was generated with them — a spec's pools and settings, families from outside the package
    (:func:`problems.generate.recorded_questions`) — or its problems."""
    from problems.generate import GenerateError, generate_assignment, recorded_questions
    from problems.roster import Roster
    from problems.templates import FAMILIES

    manifest = json.loads((a.folder / "assignment.json").read_text(encoding="utf-8"))
    try:
        families, questions = recorded_questions(manifest, a.folder, FAMILIES)
    except GenerateError as e:
        raise PackageError(f"{a.folder}: its variants cannot be generated here: "
                           f"{str(e).removeprefix('--reroll: ')}") from None
    roster = Roster(("id",), tuple({"id": v} for v in variant_ids(count)))
    generate_assignment(roster, dest, families, questions=questions, seed=manifest["seed"],
                        title=a.title)
    return dest


def info_json(a: Assignment, args: argparse.Namespace, timeout: int) -> dict:
    import uuid

    return {
        "uuid": str(uuid.uuid5(uuid.NAMESPACE_URL, f"eulertop:{a.title}:{args.name}")),
        "title": a.title, "topic": args.topic, "tags": ["eulertop"], "type": "v3",
        "gradingMethod": "External",
        "workspaceOptions": {"image": args.workspace_image, "port": 8080,
                             "home": WORKSPACE_HOME, "gradedFiles": [NOTEBOOK]},
        "externalGradingOptions": {"enabled": True, "image": args.image,
                                   "entrypoint": "/grade/tests/run", "timeout": timeout},
    }


def prairielearn_question(a: Assignment, out: Path, wheel: Path, config: dict,
                          args: argparse.Namespace) -> Path:
    """Write the question and the grading image's recipe under ``out`` (module docstring)."""
    question = out / "questions" / args.name
    if question.exists():
        raise PackageError(f"{question} exists already: remove it or choose another --out")
    limits = Limits(**config["limits"])
    timeout = min(600, int(limits.total_timeout) + 60)
    with tempfile.TemporaryDirectory(prefix="eulertop-package-") as tmp:
        pool = pool_assignment(a, args.variants, Path(tmp) / "pool")
        staged = Path(tmp) / "question"
        (staged / "variants").mkdir(parents=True)
        ids = variant_ids(args.variants)
        for v in ids:
            shutil.copyfile(pool / "release" / f"{v}.ipynb", staged / "variants" / f"{v}.ipynb")
        manifest = json.loads((pool / "assignment.json").read_text(encoding="utf-8"))
        staged_assignment(manifest, pool, pool / "key.json", staged / "tests" / "assignment")
        (staged / "tests" / CONFIG).write_text(json.dumps(config, indent=1) + "\n")
        run = staged / "tests" / "run"
        run.write_text(_text(PL_RUN, VENV=VENV))
        run.chmod(0o755)
        (staged / "info.json").write_text(json.dumps(info_json(a, args, timeout), indent=2)
                                          + "\n")
        (staged / "server.py").write_text(_text(SERVER_PY, VARIANTS=json.dumps(ids),
                                                NOTEBOOK=json.dumps(NOTEBOOK)))
        (staged / "question.html").write_text(_text(QUESTION_HTML, TITLE=a.title,
                                                    NOTEBOOK=NOTEBOOK))
        question.parent.mkdir(parents=True, exist_ok=True)
        shutil.copytree(staged, question)
        solutions = out / "solutions" / args.name  # the instructor's, outside the question
        shutil.rmtree(solutions, ignore_errors=True)
        shutil.copytree(pool / "solutions", solutions)
    image = out / "grader-image"
    image.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(wheel, image / wheel.name)
    (image / "constraints.txt").write_text("\n".join(pinned_requirements()) + "\n")
    (image / "Dockerfile").write_text(_text(DOCKERFILE, VENV=VENV, WHEEL=wheel.name))
    return question


# --------------------------------------------------------------------------------------------
# the command


def add_package_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``eulertop package``."""
    from grader.cli import seconds_argument, size_argument, whole_number_argument

    parser.add_argument("hw", type=Path, metavar="HW",
                        help="assignment folder written by 'eulertop generate'")
    parser.add_argument("--for", dest="platform", required=True, choices=PLATFORMS,
                        help="the platform to package for")
    parser.add_argument("--out", type=Path, required=True, metavar="PATH",
                        help="gradescope: the zip to write (autograder.zip); prairielearn: the "
                             "folder to write the question and the grading image into")
    parser.add_argument("--sandbox", choices=MODES, default="auto",
                        help="how student code is confined there: bubblewrap where it can "
                             "start, else the container mode (default auto)")
    parser.add_argument("--kernel-user", metavar="USER",
                        help="container mode: the unprivileged user notebooks run as "
                             "(default nobody)")
    parser.add_argument("--timeout", type=seconds_argument, metavar="S",
                        help="time limit for a whole notebook (default 120 s)")
    parser.add_argument("--cell-timeout", type=seconds_argument, metavar="S",
                        help="time limit for one cell (default 30 s)")
    parser.add_argument("--max-size", type=size_argument, metavar="SIZE",
                        help="largest submission read (default 20 MiB)")
    parser.add_argument("--wheel", type=Path, metavar="FILE",
                        help="eulertop's wheel to install there (default: built from the "
                             "source tree with 'pip wheel --no-deps')")
    parser.add_argument("--visibility", choices=("hidden", "after_due_date", "after_published",
                                                  "visible"), default="visible",
                        help="gradescope: when students see each answer's result "
                             "(default visible)")
    parser.add_argument("--variants", type=whole_number_argument, default=20, metavar="N",
                        help="prairielearn: variants made from HW's seed (default 20)")
    parser.add_argument("--name", default=None, metavar="NAME",
                        help="prairielearn: the question's folder name (default: HW's name)")
    parser.add_argument("--topic", default="Rigid-body rotation",
                        help="prairielearn: the question's topic (default %(default)r)")
    parser.add_argument("--image", default="YOUR-DOCKERHUB-USER/eulertop-grader", metavar="IMAGE",
                        help="prairielearn: the grading image built from grader-image/ "
                             "(default %(default)s)")
    parser.add_argument("--workspace-image", default=WORKSPACE_IMAGE, metavar="IMAGE",
                        help="prairielearn: the JupyterLab workspace image (default "
                             "%(default)s)")


def _wheel(args: argparse.Namespace, tmp: Path) -> Path:
    if args.wheel is None:
        return build_wheel(tmp)
    if not args.wheel.is_file() or not args.wheel.name.endswith(".whl"):
        raise PackageError(f"--wheel {args.wheel}: not a wheel file (.whl)")
    return args.wheel


def package(args: argparse.Namespace) -> Path:
    """Build the package ``args`` ask for; its path. :class:`PackageError` / ``UsageError``."""
    from grader.cli import _limits

    a = load_assignment(args.hw)
    limits = _limits(args)
    if args.kernel_user is not None and args.kernel_user.strip() in ("root", "0", ""):
        raise PackageError(f"--kernel-user {args.kernel_user!r}: name an unprivileged user")
    if args.platform == "gradescope" and args.out.suffix.lower() != ".zip":
        raise PackageError(f"--out {args.out}: Gradescope takes a .zip file")
    if args.platform == "prairielearn" and args.out.exists() and not args.out.is_dir():
        raise PackageError(f"--out {args.out}: not a folder")
    with tempfile.TemporaryDirectory(prefix="eulertop-wheel-") as tmp:
        wheel = _wheel(args, Path(tmp))
        if args.platform == "gradescope":
            config = settings(args, limits, platform="gradescope", visibility=args.visibility)
            return gradescope_zip(a, args.out, wheel, config)
        args.name = args.name or re.sub(r"[^A-Za-z0-9_-]+", "-", Path(args.hw).resolve().name)
        config = settings(args, limits, platform="prairielearn", notebook=NOTEBOOK)
        return prairielearn_question(a, args.out, wheel, config, args)


def run_package(args: argparse.Namespace) -> int:
    """Run ``eulertop package``; exit 2 with a message for a user's mistake."""
    try:
        path = package(args)
    except UsageError as e:
        print(f"eulertop package: {e}", file=sys.stderr)
        return 2
    print(f"wrote {path}")
    for line in _next_steps(args.platform, path):
        print(line)
    written = _written_note(Path(args.hw))
    if written:
        print(written)
    return 0


def _written_note(hw: Path) -> str:
    """What the platform grades by hand: the assignment's written parts (issue 31), if any."""
    from grader.assignment import load_assignment

    parts = load_assignment(hw).written()
    if not parts:
        return ""
    return (f"note: the written parts ({', '.join(parts)}) are not autograded: grade them with "
            "the platform's manual grading, their rubrics in key.json "
            "(docs/instructors/hosted.md, 'Written parts on the platform')")


def _next_steps(platform: str, path: Path) -> Iterable[str]:
    if platform == "gradescope":
        yield ("next: Gradescope → your assignment → Configure Autograder → upload this zip "
               "(base image: Ubuntu 22.04 or newer) → Update Autograder")
    else:
        yield (f"next: build and push {path.parent.parent / 'grader-image'} (docker build -t "
               "USER/eulertop-grader . && docker push USER/eulertop-grader), set that image "
               f"in {path / 'info.json'}, and commit {path} to your course repository")
