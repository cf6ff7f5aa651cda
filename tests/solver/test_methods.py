"""Every method of ``METHODS`` against the exact solution, through the one signature.

References: the exact solutions R8, R10, R20 are themselves checked against mpmath here (LL's
formula evaluated with ``mp.ellipfun``), then every method is run against them at a tight control,
and each method's order of convergence is measured for the fixed-step ones.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

from solver.asymmetric_top import asymmetric_top_period
from solver.bench.work_precision import FREE_SCENE, HEAVY_SCENE, free_reference, heavy_reference
from solver.heavy_top import nutation_period
from solver.methods import METHODS, Trajectory, solve
from solver.parameters import ParameterError
from solver.scenes import FreeBody, HeavyBody

SYMMETRIC = FreeBody(1.0, 1.0, 1.6, (0.3, -0.2, 2.0))
FREE_PERIOD = float(asymmetric_top_period(1.0, 2.0, 3.0, FREE_SCENE.omega0))
HEAVY_PERIOD = float(nutation_period(*HEAVY_SCENE.heavy_top_state()))

# the control giving ~1e-7 or better over 2 periods, per method
CONTROLS = {"RK45": 1e-10, "DOP853": 1e-10, "Radau": 1e-9, "LSODA": 1e-10, "RK4": 1 / 400,
            "LiePoisson2": 1 / 8000, "LiePoisson4": 1 / 400, "EulerAngles": 1e-10}


def _control(name, period):
    control = CONTROLS.get(name)
    return control * period if METHODS[name].control == "step" else control


CASES = {"free_asymmetric": (FREE_SCENE, FREE_PERIOD), "heavy": (HEAVY_SCENE, HEAVY_PERIOD),
         "free_symmetric": (SYMMETRIC, 1.0)}
# every (method, scene) pair that METHODS declares it answers
PAIRS = [(name, case) for name in sorted(METHODS) for case, (scene, _) in CASES.items()
         if scene.kind in METHODS[name].kinds]


@pytest.mark.parametrize(("name", "case"), PAIRS)
def test_every_method_matches_the_mpmath_reference(name, case):
    scene, period = CASES[case]
    times = np.array([0.0, 0.7 * period, 2.0 * period])
    traj = solve(scene, times, name, _control(name, period))
    assert traj.success and traj.method == name
    if scene is SYMMETRIC:  # R8 closed form in mpmath: ω1 + iω2 rotates at Ω
        with mp.workdps(40):
            omega = mp.mpf(2.0) * (mp.mpf(1.6) - 1)
            ref = [[float(mp.re(z)), float(mp.im(z)), 2.0] for z in
                   (mp.mpc(0.3, -0.2) * mp.expj(omega * mp.mpf(t)) for t in times)]
        ref = np.array(ref)
    elif scene is FREE_SCENE:
        ref = np.array([free_reference(scene, t) for t in times])
    else:
        ref = np.array([heavy_reference(scene, t) for t in times])
    tol = 1e-13 if METHODS[name].control is None else 1e-6
    assert np.max(np.abs(traj.y - ref)) < tol
    expected_cost = METHODS[name].control is not None
    assert (traj.nfev > 0) == expected_cost and (traj.nsteps > 0) == expected_cost


@pytest.mark.parametrize(("name", "order"), [("RK4", 4), ("LiePoisson2", 2), ("LiePoisson4", 4)])
def test_fixed_step_order_of_convergence(name, order):
    """Halving the step divides the error at 2 periods by ≈ 2^order (measured, against R10)."""
    times = np.array([0.0, 2.0 * FREE_PERIOD])
    exact = solve(FREE_SCENE, times, "R10").y[-1]
    errors = [np.max(np.abs(solve(FREE_SCENE, times, name, FREE_PERIOD / n).y[-1] - exact))
              for n in (100, 200)]
    assert errors[0] / errors[1] == pytest.approx(2.0**order, rel=0.15)


def test_tolerance_controls_the_error():
    times = np.array([0.0, 5.0 * FREE_PERIOD])
    exact = free_reference(FREE_SCENE, times[-1])
    for name in ("RK45", "DOP853", "LSODA"):
        loose, tight = (np.max(np.abs(solve(FREE_SCENE, times, name, r).y[-1] - exact))
                        for r in (1e-5, 1e-10))
        cost = [solve(FREE_SCENE, times, name, r).nfev for r in (1e-5, 1e-10)]
        assert tight < loose / 100 and cost[1] > cost[0]


def test_output_times_are_hit_and_returned():
    times = np.array([0.0, 0.0, 0.3, 1.7, 1.7, 4.0])
    for name in ("DOP853", "RK4", "LiePoisson2", "R10"):
        traj = solve(FREE_SCENE, times, name, _control(name, FREE_PERIOD))
        assert isinstance(traj, Trajectory)
        assert np.array_equal(traj.t, times) and traj.y.shape == (6, 3)
        assert np.array_equal(traj.y[0], FREE_SCENE.omega0)


@pytest.mark.parametrize(
    ("kwargs", "parameter"),
    [
        ({"method": "nope"}, "method"),
        ({"method": "LiePoisson2", "scene": HEAVY_SCENE, "control": 0.1}, "method"),
        ({"method": "R20"}, "method"),
        ({"method": "RK45"}, "control"),
        ({"method": "RK45", "control": -1.0}, "control"),
        ({"method": "R10", "times": [1.0, 0.5]}, "times"),
        ({"method": "R10", "times": [[0.0, 1.0]]}, "times"),
    ],
)
def test_bad_arguments_name_the_parameter(kwargs, parameter):
    args = {"scene": FREE_SCENE, "times": [0.0, 1.0], "control": None} | kwargs
    with pytest.raises(ParameterError) as info:
        solve(args["scene"], args["times"], args["method"], args["control"])
    assert info.value.parameter == parameter


def test_failure_is_a_result_not_an_exception():
    sleeping = HeavyBody(1.0, 1.0, 0.6, 1.0, 0.0, 0.0, 0.0, 10.0)
    traj = solve(sleeping, [0.0, 1.0], "EulerAngles", 1e-8)
    assert not traj.success and traj.message
