"""The SHA-256 of every file ``eulertop generate`` writes in five runs: proof that a change to the
generator left its output byte for byte as it was (issue 34: each family now draws a class at
once).

Run it with the code before and after the change and compare the printed lines::

    python benchmarks/generate_hashes.py TREE [--work DIR]

``TREE`` is the repository whose ``eulertop`` runs (each command a fresh process, as an
instructor's, with ``TREE`` first on the path). The runs, into ``DIR`` (a temporary folder by
default):

1. ``plain``: 12 students, every built-in family, ``--seed 11`` (this process only: fewer than
   ``PARALLEL_MIN`` students);
2. ``spec``: 24 students from a spec — a pool of two families, points, a widened tolerance, a
   fixed parameter and a narrowed range, ``follow_through``, and a family from a folder (the
   example of ``eulertop new-family``);
3. ``class``: 48 students, every built-in family, ``--seed 5``, drawn by the forked workers;
4. ``reroll``: a copy of ``class`` with students ``s003`` and ``s017`` rerolled;
5. ``force``: ``class`` generated again over itself with ``--force`` and a student more.

It prints, per run, each file's path and hash, then one digest of the run and of everything.
"""

from __future__ import annotations

import argparse
import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

SPEC = """title = "hash check"
seed = 23
roster = "roster24.csv"
families = ["mine"]
follow_through = 0.5

[[questions]]
family = "turning_points"
points = 6

[[questions]]
pool = ["sleeping_top", "steady_precession"]
points = 4

[[questions]]
family = "inertia_tensor"
[questions.answers.I_diag]
rtol = 5e-3

[[questions]]
family = "nutation_precession"
[questions.parameters]
beta0 = [0.4, 0.9]

[[questions]]
family = "thrown_ball"
[questions.parameters]
v0 = 12.0
"""


def roster(path: Path, n: int) -> Path:
    path.write_text("id,name\n" + "".join(f"s{i:03d},Student {i}\n" for i in range(n)),
                    encoding="utf-8")
    return path


def eulertop(tree: Path, *args: str) -> None:
    env = {**os.environ, "PYTHONPATH": str(tree)}
    subprocess.run([sys.executable, "-m", "eulertop", *args], cwd=tree, env=env, check=True,
                   stdout=subprocess.DEVNULL)


def hashes(folder: Path) -> list[str]:
    """``path sha256`` of every file under ``folder``, sorted by path."""
    return [f"{p.relative_to(folder).as_posix()} {hashlib.sha256(p.read_bytes()).hexdigest()}"
            for p in sorted(folder.rglob("*")) if p.is_file()]


def runs(tree: Path, work: Path) -> dict[str, Path]:
    """The five runs of the module docstring, into ``work``."""
    eulertop(tree, "generate", "--roster", str(roster(work / "roster12.csv", 12)),
             "--out", str(work / "plain"), "--seed", "11")
    eulertop(tree, "new-family", "thrown_ball", "--out", str(work / "mine"))
    roster(work / "roster24.csv", 24)
    (work / "spec.toml").write_text(SPEC, encoding="utf-8")
    eulertop(tree, "generate", "--spec", str(work / "spec.toml"), "--out", str(work / "spec"))
    eulertop(tree, "generate", "--roster", str(roster(work / "roster48.csv", 48)),
             "--out", str(work / "class"), "--seed", "5")
    shutil.copytree(work / "class", work / "reroll")
    eulertop(tree, "generate", "--out", str(work / "reroll"), "--reroll", "s003",
             "--reroll", "s017")
    shutil.copytree(work / "class", work / "force")
    eulertop(tree, "generate", "--roster", str(roster(work / "roster49.csv", 49)),
             "--out", str(work / "force"), "--force")
    return {name: work / name for name in ("plain", "spec", "class", "reroll", "force")}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("tree", type=Path, help="the repository whose eulertop runs")
    parser.add_argument("--work", type=Path, help="folder for the runs (default: temporary)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        work = args.work or Path(tmp)
        work.mkdir(parents=True, exist_ok=True)
        everything = hashlib.sha256()
        for name, folder in runs(args.tree.resolve(), work).items():
            lines = hashes(folder)
            digest = hashlib.sha256("\n".join(lines).encode()).hexdigest()
            everything.update(digest.encode())
            print("\n".join(f"{name}/{line}" for line in lines))
            print(f"run {name}: {len(lines)} files, digest {digest}")
        print(f"all runs: digest {everything.hexdigest()}")


if __name__ == "__main__":
    main()
