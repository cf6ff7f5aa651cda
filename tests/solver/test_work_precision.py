"""``eulertop bench --quick``: the files it writes, and that their numbers make sense."""

from __future__ import annotations

import csv
import math
import sys

import numpy as np
import pytest

from eulertop.cli import main
from solver.work_precision import rank_at_accuracy


@pytest.fixture(scope="module")
def bench_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench")
    assert main(["bench", "--quick", "--out", str(out)]) == 0
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

    code = "import sys, solver.work_precision; print('matplotlib' in sys.modules)"
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
    assert "Smallest error each adaptive method reached" in summary


def test_scenes_table_covers_states_and_horizons(bench_dir):
    """Generic, near the vertical, near the separatrix and fast states, each at every horizon:
    the exact model stays at rounding, DOP853 (rtol 1e-13) loses accuracy near the separatrix
    as the horizon grows (the phenomenon, not a margin)."""
    from solver.work_precision import scene_states

    rows = _rows(bench_dir / "scenes.csv")
    assert {r["scene"] for r in rows} == set(scene_states())
    assert {r["periods"] for r in rows} == {"1", "10"}
    exact = [float(r["error"]) for r in rows if r["method"] in ("R10", "R20")]
    assert max(exact) < 1e-12
    sep = {r["periods"]: float(r["error"]) for r in rows
           if r["scene"] == "free, near the separatrix" and r["method"] == "DOP853"}
    assert sep["10"] > sep["1"]
