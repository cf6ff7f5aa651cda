"""`eulertop solve`: one case for a person, and the JSON-lines batch (issue 2's contract)."""

from __future__ import annotations

import io
import json
import math
import subprocess
import sys

import numpy as np
import pytest

from eulertop.cli import main
from solver.cli import SCENES, solve_lines
from solver.heavy_top import solve_heavy_top

HEAVY = {"I1": 2.0e-4, "I3": 1.0e-4, "Mgl": 0.02, "beta0": 0.5,
         "alpha_dot0": 0.3, "beta_dot0": 0.0, "gamma_dot0": 150.0}
HEAVY_OUT = ("p_alpha", "p_gamma", "E_prime", "beta1", "beta2", "alpha_dot_beta1",
             "alpha_dot_beta2", "nutation_period", "mean_precession_rate", "motion",
             "sleeping_stable", "omega3_critical", "steady_precession_rates", "undefined")


def run_batch(lines: list[str], monkeypatch, capsys, *extra: str) -> tuple[int, list[dict]]:
    monkeypatch.setattr(sys, "stdin", io.StringIO("\n".join(lines) + "\n"))
    status = main(["solve", *extra, "--batch", "-"])
    out = capsys.readouterr().out
    return status, [json.loads(line) for line in out.splitlines()]


def test_heavy_top_fields_exactly(monkeypatch, capsys):
    status, [answer] = run_batch([json.dumps({"scene": "heavy-top", **HEAVY})], monkeypatch, capsys)
    assert status == 0
    assert tuple(answer) == HEAVY_OUT
    # R15 by hand (independent of the solver): p_γ = I3 (α̇ cos β + γ̇), p_α = I1 α̇ sin²β + p_γ cos β
    p_gamma = HEAVY["I3"] * (HEAVY["alpha_dot0"] * math.cos(0.5) + HEAVY["gamma_dot0"])
    p_alpha = HEAVY["I1"] * 0.3 * math.sin(0.5) ** 2 + p_gamma * math.cos(0.5)
    assert answer["p_gamma"] == pytest.approx(p_gamma, rel=1e-13)
    assert answer["p_alpha"] == pytest.approx(p_alpha, rel=1e-13)
    assert answer["beta1"] <= 0.5 + 1e-12 <= answer["beta2"] + 2e-12
    assert answer["motion"] in ("waves", "loops", "cusps")


def test_batch_keeps_order_echoes_ids_and_isolates_bad_lines(monkeypatch, capsys):
    lines = [
        json.dumps({"id": "a", "scene": "heavy-top", **HEAVY}),
        json.dumps({"id": "b", "scene": "heavy-top", **{**HEAVY, "I1": -1.0}}),
        "this is not json",
        json.dumps({"id": "d", "scene": "free-top", "I1": 1, "I2": 2, "I3": 3,
                    "omega0": [0.1, 0.2, 3.0]}),
        json.dumps([1, 2, 3]),
        json.dumps({"id": "f", "scene": "heavy-top", **{**HEAVY, "Mgl": "heavy"}}),
    ]
    status, answers = run_batch(lines, monkeypatch, capsys)
    assert status == 1
    assert [a.get("id") for a in answers] == ["a", "b", None, "d", None, "f"]
    assert "error" not in answers[0] and "error" not in answers[3]
    assert answers[1]["error"].startswith("I1:")
    assert "line 3" in answers[2]["error"] and "JSON" in answers[2]["error"]
    assert "line 5" in answers[4]["error"]
    assert answers[5]["error"].startswith("Mgl:")


@pytest.mark.parametrize(
    ("case", "field"),
    [
        ({"scene": "heavy-top", **{k: v for k, v in HEAVY.items() if k != "beta0"}}, "beta0"),
        ({"scene": "heavy-top", **HEAVY, "mass": 1.0}, "mass"),
        ({"scene": "heavy-top", **{**HEAVY, "I3": None}}, "I3"),
        ({"scene": "heavy-top", **{**HEAVY, "beta0": True}}, "beta0"),
        ({"scene": "free-top", "I1": 1, "I2": 2, "I3": 3, "omega0": [1, 2]}, "omega0"),
        ({"scene": "free-top", "I1": 1, "I2": 1, "I3": 3, "omega0": [1, 2, 3]}, "I3"),
        ({"scene": "free-top", "I1": 1, "I2": 2, "I3": 0, "omega0": [1, 2, 3]}, "I3"),
        ({"scene": "euler-angles", "alpha": 0, "beta": 1, "gamma": 0, "alpha_dot": 0,
          "beta_dot": 0, "gamma_dot": 1, "I1": 1.0}, "I2"),
        ({"scene": "inertia", "masses": [1, -2], "positions": [[0, 0, 1], [1, 0, 0]]}, "masses"),
        ({"scene": "inertia", "masses": [1, 2]}, "positions"),
        ({"scene": "warp-drive"}, "scene"),
        ({"I1": 1}, "scene"),
    ],
)
def test_bad_input_names_the_field(case, field, monkeypatch, capsys):
    status, [answer] = run_batch([json.dumps(case)], monkeypatch, capsys)
    assert status == 1
    assert set(answer) == {"error"}
    assert answer["error"].startswith(f"{field}:"), answer["error"]


def test_scene_on_command_line_applies_to_every_line(monkeypatch, capsys):
    status, answers = run_batch([json.dumps(HEAVY)] * 3, monkeypatch, capsys, "heavy-top")
    assert status == 0 and len(answers) == 3 and answers[0] == answers[2]


def test_nothing_non_finite_is_printed_sleeping_top(monkeypatch, capsys):
    # A stable sleeping top (β0 = 0, spin far above critical): no nutation period exists.
    sleeping = {**HEAVY, "beta0": 0.0, "alpha_dot0": 0.0, "gamma_dot0": 400.0}
    status, [answer] = run_batch([json.dumps({"scene": "heavy-top", **sleeping})],
                                 monkeypatch, capsys)
    assert status == 0
    assert answer["motion"] == "sleeping" and answer["sleeping_stable"] is True
    assert answer["beta1"] == 0.0 and answer["beta2"] == 0.0
    # no nutation: the period is the limit, 2π I1/√(p_γ² − 4 I1 Mgl) (R19's small oscillation)
    pg = HEAVY["I3"] * 400.0
    assert answer["nutation_period"] == pytest.approx(
        2 * math.pi * HEAVY["I1"] / math.sqrt(pg**2 - 4 * HEAVY["I1"] * HEAVY["Mgl"]), rel=1e-12)
    assert answer["mean_precession_rate"] is None
    assert "vertical" in answer["undefined"]["mean_precession_rate"]
    numbers = [v for v in answer.values() if isinstance(v, float)]
    assert numbers and all(math.isfinite(v) for v in numbers)


def test_free_top_period_on_the_separatrix_is_null(monkeypatch, capsys):
    # On the separatrix L² = 2T I2 exactly in binary floating point (R10): with ω = (w1, 0, w3),
    # I1 (I2 − I1) w1² = I3 (I3 − I2) w3²; I = (1/2, 5/4, 3/2), w1 = w3 = 1/2 gives 3/8 = 3/8
    # (2T = 1/2, L² = 5/8 = 2T I2).
    case = {"scene": "free-top", "I1": 0.5, "I2": 1.25, "I3": 1.5, "omega0": [0.5, 0.0, 0.5]}
    status, [answer] = run_batch([json.dumps(case)], monkeypatch, capsys)
    assert status == 0 and answer["period"] is None


def test_inertia_point_masses_by_hand(monkeypatch, capsys):
    # Two unit masses at ±x: I = diag(0, 2, 2) (R2 by hand).
    case = {"scene": "inertia", "masses": [1.0, 1.0], "positions": [[1, 0, 0], [-1, 0, 0]]}
    status, [answer] = run_batch([json.dumps(case)], monkeypatch, capsys)
    assert status == 0
    np.testing.assert_allclose(answer["tensor"], np.diag([0.0, 2.0, 2.0]), atol=1e-15)
    np.testing.assert_allclose(answer["principal_moments"], [0.0, 2.0, 2.0], atol=1e-15)
    assert np.linalg.det(np.array(answer["principal_axes"])) == pytest.approx(1.0)


def test_one_case_for_a_person(capsys):
    args = [f"--{k}={v}" for k, v in HEAVY.items()]
    assert main(["solve", "heavy-top", *args]) == 0
    table = capsys.readouterr().out
    assert "beta1" in table and "rad" in table and "nutation_period" in table
    assert main(["solve", "heavy-top", *args, "--json"]) == 0
    assert tuple(json.loads(capsys.readouterr().out)) == HEAVY_OUT


@pytest.mark.parametrize("scene", list(SCENES))
def test_every_scene_solves_its_builtin_example(scene, capsys):
    assert main(["solve", scene]) == 0
    out, err = capsys.readouterr()
    assert "built-in example" in err and out.strip()


def test_one_case_error_exits_1_with_message(capsys):
    assert main(["solve", "free-top", "--I1", "1", "--I2", "2", "--I3", "3"]) == 1
    assert "omega0: missing" in capsys.readouterr().err


def test_usage_errors_exit_2(capsys, tmp_path):
    assert main(["solve"]) == 2
    assert main(["solve", "--batch", str(tmp_path / "nope.jsonl")]) == 2
    assert "cannot read" in capsys.readouterr().err


def test_batch_solutions_equal_single_solutions():
    rng = np.random.default_rng(7)
    cases = [{**HEAVY, "beta0": float(b), "gamma_dot0": float(g)}
             for b, g in zip(rng.uniform(0.2, 2.5, 5), rng.uniform(80, 400, 5), strict=True)]
    lines = [json.dumps({"scene": "heavy-top", **c}) for c in cases]
    lines.insert(2, json.dumps({"scene": "heavy-top", **{**HEAVY, "Mgl": -1.0}}))
    batch = list(solve_lines(lines, chunk=2))  # chunk boundaries, and a bad state inside one
    assert batch.pop(2)["error"].startswith("Mgl:")
    for case, answer in zip(cases, batch, strict=True):
        assert answer == {k: v for k, v in solve_heavy_top(**case).items()}


def test_console_script_end_to_end(tmp_path):
    cases = tmp_path / "cases.jsonl"
    cases.write_text(json.dumps({"scene": "heavy-top", **HEAVY}) + "\n", encoding="utf-8")
    proc = subprocess.run([sys.executable, "-m", "eulertop", "solve", "--batch", str(cases)],
                          capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert tuple(json.loads(proc.stdout)) == HEAVY_OUT
