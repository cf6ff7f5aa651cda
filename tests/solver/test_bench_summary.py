"""The bench's text is written by the bench: the block of the site's page ``docs/speed.md`` and
``docs/bench/summary.md`` are what the committed CSVs render to, and no measured number stands
outside the block."""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path

import pytest

from solver.bench.summary import (
    BEGIN,
    END,
    BlockError,
    current_block,
    load_results,
    markers_of,
    page_block,
    replace_block,
    summary_markdown,
)
from solver.bench.work_precision import BenchConfig

ROOT = Path(__file__).resolve().parents[2]
BENCH = ROOT / "docs" / "bench"
PAGE = (ROOT / "docs" / "speed.md").read_text(encoding="utf-8")
SPEED_BENCHES = ("bench_heavy_top", "bench_generate", "bench_startup")


@pytest.fixture(scope="module")
def committed():
    return load_results(BENCH)


def test_page_block_is_what_the_committed_csvs_render_to(committed):
    """A hand edit of any number in the page's block (or of a CSV) fails here."""
    results, run = committed
    assert current_block(PAGE) == page_block(results, run, "bench/")


def test_summary_md_is_what_the_committed_csvs_render_to(committed):
    results, run = committed
    summary = (BENCH / "summary.md").read_text(encoding="utf-8")
    assert summary == summary_markdown(results, run)
    assert page_block(results, run, "") in summary  # the page's text, charts beside it


def test_committed_run_is_the_documented_full_run(committed):
    _, run = committed
    assert run["command"] == "eulertop bench --out docs/bench --page docs/speed.md"
    full = dataclasses.asdict(BenchConfig.full())
    assert run["config"] == {k: list(v) if isinstance(v, tuple) else v for k, v in full.items()}
    assert run["wall_seconds"] > 0 and run["cpu_count"] >= 1
    block = current_block(PAGE)
    for fact in (run["command"], run["date"], run["python"], run["numpy"],
                 f"{run['wall_seconds']:.0f} s"):
        assert fact in block


def test_no_measured_number_outside_the_block():
    """The page's hand-written prose states no measurement: numbers live in the blocks (this
    bench's, and those the benchmarks of issue 34 write: tests/test_speed_page.py)."""
    prose = PAGE
    for markers in [(BEGIN, END), *(markers_of(bench) for bench in SPEED_BENCHES)]:
        prose = prose.replace(current_block(PAGE, "docs/speed.md", markers), "")
    prose = re.sub(r"`[^`]*`", "", prose)  # code spans: commands and names
    measured = re.findall(r"\d+\.\d+|\d(?:\.\d+)?e[-+]?\d+|\d+\s?(?:ms|µs|s|×|%)(?!\w)", prose)
    assert measured == []


def test_replace_block_replaces_only_between_the_markers():
    text = f"intro\n{BEGIN}\nold 1.0\n{END}\noutro\n"
    new = f"{BEGIN}\nnew 2.0\n{END}\n"
    assert replace_block(text, new) == f"intro\n{new}outro\n"
    assert current_block(replace_block(text, new)) == new


@pytest.mark.parametrize("text", ["no markers\n", f"{BEGIN}\nx\n", f"{END}\n{BEGIN}\n",
                                  f"{BEGIN}\n{BEGIN}\n{END}\n"])
def test_replace_block_names_the_file_when_markers_are_wrong(text):
    with pytest.raises(BlockError, match=re.escape("notes/speed.md")):
        replace_block(text, "", "notes/speed.md")


def _sweep(method, floor, tightest=1e-14):
    """A method whose error follows rtol down to ``floor``, then stays there."""
    rtols = [10.0**-k for k in range(3, 15) if 10.0**-k >= tightest]
    return [{"method": method, "control": r, "error": max(r, floor), "seconds": 1e-3 / r**0.2,
             "repeats": 1, "nfev": int(100 / r**0.2), "nsteps": 1, "success": True}
            for r in rtols]


def test_a_method_that_never_reaches_an_accuracy_is_said_to_stall_there():
    """From the data alone: DOP853 with a floor of 2e-12 gets '—' at 1e-12 and 'stalls at 2e-12';
    a method reaching 1e-12 gets a cost; none is extrapolated."""
    from solver.bench.summary import _equal_accuracy
    from solver.bench.work_precision import FREE_SCENE

    rows = [*_sweep("DOP853", 2e-12), *_sweep("LSODA", 1e-13),
            {"method": "R10", "control": None, "error": 3e-14, "seconds": 3e-4, "repeats": 3,
             "nfev": 0, "nsteps": 0, "success": True}]
    text = "\n".join(_equal_accuracy(rows, "Free top", "100 periods", FREE_SCENE, "free"))
    dop = next(line for line in text.splitlines() if line.startswith("| DOP853 |"))
    assert dop.split(" | ")[3] == "—"  # the 1e-12 column
    assert "DOP853 stalls at 2e-12" in text and "reached by LSODA" in text
    assert "R10 is at 3e-14" in text


def test_fast_top_table_follows_the_closed_form(committed):
    """R21's relative errors against their closed forms with x = 2 ε cos β0: slow
    (√(1 − x) − 1)/2, fast 2/(1 + √(1 − x)) − 1 (first order ∓ ε cos β0 / 2)."""
    results, _ = committed
    for row in results["fast_top"]:
        x = 2 * row["epsilon"] * math.cos(row["beta0_rad"])
        assert row["slow_error"] == pytest.approx((math.sqrt(1 - x) - 1) / 2, rel=1e-9, abs=1e-15)
        assert row["fast_error"] == pytest.approx(2 / (1 + math.sqrt(1 - x)) - 1, rel=1e-9,
                                                  abs=1e-15)
