"""The speed page's figures against their floors (issue 34) are written by their benchmarks:
each block of ``docs/speed.md`` between ``<!-- <bench>: begin -->`` and ``<!-- <bench>: end -->``
is what ``benchmarks/<bench>.py`` renders from its committed record in ``docs/bench/``, so a
number edited by hand (on the page or in the record) fails here."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

from solver.bench.summary import BlockError, current_block, markers_of, replace_block

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "speed.md"
RECORDS = {"bench_heavy_top": "heavy_top.json", "bench_generate": "generate.json",
           "bench_startup": "startup.json"}


def _bench(name: str):
    """The benchmark script ``benchmarks/<name>.py``, imported as a module."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    return module


def _rendered(name: str, record: dict) -> str:
    bench = _bench(name)
    render = bench.render_margin if name == "bench_generate" else bench.render
    begin, end = markers_of(name)
    return "\n".join([begin, *render(record), end]) + "\n"


@pytest.mark.parametrize("name", sorted(RECORDS))
def test_each_block_is_what_its_record_renders_to(name):
    record = json.loads((ROOT / "docs" / "bench" / RECORDS[name]).read_text(encoding="utf-8"))
    page = PAGE.read_text(encoding="utf-8")
    block = current_block(page, str(PAGE), markers_of(name))
    assert block == _rendered(name, record)
    assert record["command"] in page.replace(block, "")  # the page names the command above
    assert record["machine"]["load"] and record["load_after"]  # and the block, the load


def test_a_changed_timing_changes_the_text():
    """The control: the rendering reads the record's timings (a hand edit cannot survive)."""
    record = json.loads((ROOT / "docs" / "bench" / "heavy_top.json").read_text(encoding="utf-8"))
    before = _rendered("bench_heavy_top", record)
    for row in record["times"]["ours"]:
        row["wall"] *= 1.5
    assert _rendered("bench_heavy_top", record) != before


def test_a_block_of_another_bench_is_left_alone():
    text = "a\n<!-- x: begin -->\nold\n<!-- x: end -->\n<!-- y: begin -->\nkeep 1.0\n" \
           "<!-- y: end -->\n"
    new = replace_block(text, "<!-- x: begin -->\nnew\n<!-- x: end -->\n", "p", markers_of("x"))
    assert "new" in new and "keep 1.0" in new and "old" not in new
    with pytest.raises(BlockError, match="p: needs one line '<!-- z: begin -->'"):
        current_block(text, "p", markers_of("z"))


def test_the_cost_of_one_more_student_pairs_each_rounds_two_calls():
    """bench_generate's margin is the median over rounds of (large − small) / added, each
    round's two calls taken together: a slow round slows both of its calls, not the margin
    (the difference of the two medians would mix a fast round's call with a slow one's)."""
    bench = _bench("bench_generate")
    record = {"students": [100, 200], "generate": {"disk": {
        "100": [1.0, 2.0, 3.0], "200": [1.2, 2.2, 3.2]}}}
    small, large, margin = bench._margin(record, "generate", "disk")
    assert (small, large) == (2.0, 2.2)
    assert margin == pytest.approx(0.2 / 100)
    record["generate"]["disk"]["200"] = [3.2, 1.2, 2.2]  # the same calls, rounds shuffled
    assert bench._margin(record, "generate", "disk")[2] != pytest.approx(0.2 / 100)


def test_the_generation_parts_say_how_the_collector_ran():
    """A record says whether its parts were timed with the cycle collector paused, as the
    generator's workers run (``collector``); the text says so only where the record does."""
    record = json.loads((ROOT / "docs" / "bench" / "generate.json").read_text(encoding="utf-8"))
    said = "cycle collector paused"
    record.pop("collector", None)
    assert said not in _rendered("bench_generate", record)
    record["collector"] = _bench("bench_generate").COLLECTOR
    assert said in _rendered("bench_generate", record)
