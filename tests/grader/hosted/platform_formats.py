"""The platforms' documented results formats, as small checks (no code of eulertop's).

Gradescope: "Autograder Specifications", Output format (gradescope/autograder_samples,
docs/specs.md). PrairieLearn: "External Grading", Grading results (PrairieLearn/PrairieLearn,
docs/externalGrading.md) and the ``<pl-external-grader-results>`` example there.
"""

from __future__ import annotations

import json
from numbers import Real
from pathlib import Path

GRADESCOPE_TOP = {"score", "execution_time", "output", "output_format", "test_output_format",
                  "test_name_format", "visibility", "stdout_visibility", "extra_data", "tests",
                  "leaderboard"}
GRADESCOPE_TEST = {"score", "max_score", "status", "name", "name_format", "number", "output",
                   "output_format", "tags", "visibility", "extra_data"}
GRADESCOPE_VISIBILITY = {"hidden", "after_due_date", "after_published", "visible"}

PRAIRIELEARN_TOP = {"gradable", "score", "message", "output", "images", "tests", "format_errors"}
PRAIRIELEARN_TEST = {"name", "description", "points", "max_points", "message", "output",
                     "images"}
PRAIRIELEARN_MAX_BYTES = 1024**2


def _number(value: object) -> bool:
    return isinstance(value, Real) and not isinstance(value, bool)


def check_gradescope(path: Path) -> dict:
    """``results.json`` read and checked against Gradescope's documented fields; the dict."""
    results = json.loads(Path(path).read_text(encoding="utf-8"))
    assert isinstance(results, dict)
    assert set(results) <= GRADESCOPE_TOP, set(results) - GRADESCOPE_TOP
    tests = results.get("tests", [])
    # "score": optional, but required if not on each test case
    assert "score" in results or all("score" in t for t in tests)
    if "score" in results:
        assert _number(results["score"])
    if "execution_time" in results:
        assert _number(results["execution_time"])
    if "output" in results:
        assert isinstance(results["output"], str)
    assert isinstance(tests, list)
    for t in tests:
        assert set(t) <= GRADESCOPE_TEST, set(t) - GRADESCOPE_TEST
        for k in ("score", "max_score"):
            assert k not in t or _number(t[k])
        for k in ("name", "output"):
            assert k not in t or isinstance(t[k], str)
        assert t.get("visibility", "visible") in GRADESCOPE_VISIBILITY
    return results


def check_prairielearn(path: Path) -> dict:
    """``results.json`` read and checked against PrairieLearn's documented fields; the dict."""
    path = Path(path)
    assert path.stat().st_size <= PRAIRIELEARN_MAX_BYTES  # "limited to 1 MB"
    results = json.loads(path.read_text(encoding="utf-8"))
    assert isinstance(results, dict)
    assert set(results) <= PRAIRIELEARN_TOP, set(results) - PRAIRIELEARN_TOP
    gradable = results.get("gradable", True)
    assert isinstance(gradable, bool)
    if gradable:  # "score ... a floating point number in the range [0.0, 1.0]"
        assert _number(results["score"]) and 0.0 <= results["score"] <= 1.0
    if "message" in results:
        assert isinstance(results["message"], str)
    for t in results.get("tests", []):
        assert set(t) <= PRAIRIELEARN_TEST, set(t) - PRAIRIELEARN_TEST
        assert isinstance(t["name"], str)
        assert _number(t["points"]) and _number(t["max_points"])
        assert 0 <= t["points"] <= t["max_points"]
        assert "message" not in t or isinstance(t["message"], str)
    return results
