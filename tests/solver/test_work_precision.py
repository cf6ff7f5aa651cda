"""``eulertop bench --quick``: the files it writes, and that their numbers make sense."""

from __future__ import annotations

import csv
import math
import sys

import numpy as np
import pytest

from eulertop.cli import main
from solver.bench.work_precision import rank_at_accuracy

PAGE_BEFORE = "# Notes\n\nprose 1.5 s\n\n<!-- eulertop bench: begin -->\nstale 9.9 s\n"
PAGE_AFTER = "<!-- eulertop bench: end -->\n\n## Next\n"


@pytest.fixture(scope="module")
def bench_dir(tmp_path_factory):
    root = tmp_path_factory.mktemp("bench")
    (root / "docs").mkdir()
    (root / "docs" / "speed.md").write_text(PAGE_BEFORE + PAGE_AFTER)
    out = root / "docs" / "bench"
    assert main(["bench", "--quick", "--out", str(out), "--page",
                 str(root / "docs" / "speed.md")]) == 0
    return out


def _rows(path):
    with path.open() as fh:
        return list(csv.DictReader(fh))


def test_files_are_written(bench_dir):
    for name in ("wp_free_time.png", "wp_free_nfev.png", "wp_heavy_time.png",
                 "wp_heavy_nfev.png", "turning_points.png", "drift.png"):
        assert (bench_dir / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    for name in ("wp_free.csv", "wp_heavy.csv", "turning_points.csv", "drift.csv"):
        assert len(_rows(bench_dir / name)) > 3
    summary = (bench_dir / "summary.md").read_text()
    assert "Ranking at equal accuracy" in summary and "Invariant drift" in summary


def test_exact_models_are_exact_and_free(bench_dir):
    for name, model in (("wp_free.csv", "R10"), ("wp_heavy.csv", "R20")):
        row = next(r for r in _rows(bench_dir / name) if r["method"] == model)
        assert float(row["error"]) < 1e-13 and int(row["nfev"]) == 0


def test_tighter_tolerance_is_more_accurate(bench_dir):
    rows = [r for r in _rows(bench_dir / "wp_free.csv") if r["method"] == "DOP853"]
    errors = [float(r["error"]) for r in sorted(rows, key=lambda r: -float(r["control"]))]
    assert errors[-1] < errors[0] / 1e4


def test_lie_poisson_keeps_L2_others_drift(bench_dir):
    last = {r["method"]: r for r in _rows(bench_dir / "drift.csv")}
    assert float(last["LiePoisson2"]["L2_error"]) < 1e-12
    assert float(last["RK45"]["L2_error"]) > 1e-8


def test_rank_at_accuracy_interpolates_log_log():
    rows = [{"method": "A", "control": c, "error": e, "seconds": s, "nfev": n}
            for c, e, s, n in ((1e-3, 1e-3, 1.0, 100), (1e-6, 1e-7, 10.0, 1000))]
    rows.append({"method": "X", "control": None, "error": 1e-15, "seconds": 0.01, "nfev": 0})
    ranked = rank_at_accuracy(rows, 1e-5)
    assert [r["method"] for r in ranked] == ["X", "A"]
    assert ranked[1]["seconds"] == pytest.approx(10**0.5) and math.isfinite(ranked[1]["nfev"])


def test_import_is_light():
    """Importing the bench module must not import matplotlib (the CLI stays fast)."""
    import subprocess

    code = "import sys, solver.bench.work_precision; print('matplotlib' in sys.modules)"
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=str(np.__file__ and __file__.rsplit("/tests/", 1)[0]))
    assert res.stdout.strip() == "False"


def test_errors_are_sampled_off_period_multiples(bench_dir):
    """Errors and drift are measured at times that are not period multiples (a periodic error
    vanishes there), and the summary names the error it reports."""
    periods = [float(r["periods"]) for r in _rows(bench_dir / "drift.csv")]
    assert all(abs(p - round(p)) > 0.1 for p in periods)
    summary = (bench_dir / "summary.md").read_text()
    assert "max over sampled t of |cos β(t) − cos β_ref(t)|" in summary
    assert "Smallest error each method's sweep reached" in summary


def test_scenes_table_covers_states_and_horizons(bench_dir):
    """Generic, near the vertical, near the separatrix and fast states, each at every horizon:
    the exact model stays at rounding, DOP853 (rtol 1e-13) loses accuracy near the separatrix
    as the horizon grows (the phenomenon, not a margin)."""
    from solver.bench.work_precision import scene_states

    rows = _rows(bench_dir / "scenes.csv")
    assert {r["scene"] for r in rows} == set(scene_states())
    assert {r["periods"] for r in rows} == {"1", "10"}
    exact = [float(r["error"]) for r in rows if r["method"] in ("R10", "R20")]
    assert max(exact) < 1e-12
    sep = {r["periods"]: float(r["error"]) for r in rows
           if r["scene"] == "free, near the separatrix" and r["method"] == "DOP853"}
    assert sep["10"] > sep["1"]


def test_page_block_is_written_from_the_run_files(bench_dir):
    """--page replaces only the block, with the text the run's files render to (chart links
    relative to the page), and summary.md opens with the same text."""
    from solver.bench.summary import load_results, page_block

    page = (bench_dir.parent / "speed.md").read_text()
    results, run = load_results(bench_dir)
    block = page_block(results, run, "bench/")
    assert page == "# Notes\n\nprose 1.5 s\n\n" + block + "\n## Next\n"
    assert "stale" not in page and "](bench/wp_free_time.png)" in page
    assert run["command"].startswith("eulertop bench --out ") and "--quick" in run["command"]
    assert run["command"].endswith("--page " + str(bench_dir.parent / "speed.md"))
    assert page_block(results, run, "") in (bench_dir / "summary.md").read_text()


def test_bad_page_stops_before_measuring(tmp_path, capsys):
    """A page without the markers: exit 2 and a message naming it, before minutes of work."""
    page = tmp_path / "speed.md"
    page.write_text("# no markers\n")
    out = tmp_path / "out"
    assert main(["bench", "--quick", "--out", str(out), "--page", str(page)]) == 2
    err = capsys.readouterr().err
    assert str(page) in err and "eulertop bench: end" in err
    assert not out.exists()
    missing = tmp_path / "nope.md"
    assert main(["bench", "--out", str(out), "--page", str(missing)]) == 2
    assert str(missing) in capsys.readouterr().err


def test_stability_battery_ours_at_rounding_naive_loses_digits(bench_dir):
    """The measured battery shows the phenomena (against mpmath or a closed form)."""
    rows = _rows(bench_dir / "stability.csv")

    def errors(method):
        return [float(r["error"]) for r in rows if r["method"] == method]

    assert max(errors("cubic_roots")) < 4e-16 and max(errors("np.roots")) > 1e-10
    assert max(errors("flip_time")) < 1e-15 and max(errors("DOP853, rtol 1e-10")) > 1e-6
    assert max(errors("Carlson R_F")) < 1e-15
    assert max(errors("quaternions")) < 5e-10
    euler = [r for r in rows if r["method"] == "Euler angles"]
    assert any(r["note"] for r in euler)  # the sleeping top: Euler angles divide by sin 0
    assert max(float(r["error"]) for r in euler if not r["note"]) > 1e-8
