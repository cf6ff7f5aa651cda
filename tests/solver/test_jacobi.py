"""Jacobi elliptic functions near the separatrix m → 1 (R10, R20) against mpmath at 40+ digits."""

from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.special import ellipj

from solver.jacobi import incomplete_f, jacobi_sncndn

M1_CASES = [0.5, 1e-3, 1e-6, 2.0**-40, 1e-15, 1e-30, 1e-200]


@pytest.mark.parametrize("m1", M1_CASES)
def test_jacobi_functions_near_m_equal_one(m1):
    with mp.workdps(40 - int(np.log10(m1))):  # 40 digits of m1 itself, not only of m
        m = 1 - mp.mpf(m1)
        K = float(mp.ellipk(m))
        u = np.linspace(-3.2 * K, 5.3 * K, 23)
        reference = np.array(
            [[float(mp.ellipfun(f, mp.mpf(x), m=m)) for f in ("sn", "cn", "dn")] for x in u]
        )
    values = np.stack(jacobi_sncndn(u, np.full_like(u, m1)), axis=-1)
    assert_allclose(values, reference, rtol=0, atol=2e-14)


def test_scipy_ellipj_fails_where_landen_does_not():
    """The reason this module exists: scipy's ellipj near m = 1 (measured, not assumed)."""
    m1 = 2.0**-40
    with mp.workdps(60):
        m = 1 - mp.mpf(m1)
        K = float(mp.ellipk(m))
        u = np.linspace(1.5 * K, 2.5 * K, 41)
        reference = np.array([float(mp.ellipfun("sn", mp.mpf(x), m=m)) for x in u])
    naive = np.max(np.abs(ellipj(u, 1.0 - m1)[0] - reference))
    ours = np.max(np.abs(jacobi_sncndn(u, m1)[0] - reference))
    assert naive > 1e-6  # scipy: garbage near u = 2K
    assert ours < 2e-14


@pytest.mark.parametrize("m1", M1_CASES)
@pytest.mark.parametrize("phi", [-1.2, 0.3, 1.0, np.pi / 2])
def test_incomplete_f_against_mpmath(m1, phi):
    with mp.workdps(40 - int(np.log10(m1))):
        reference = float(mp.ellipf(mp.mpf(phi), 1 - mp.mpf(m1)))
    value = incomplete_f(np.sin(phi), np.cos(phi), m1)
    assert value == pytest.approx(reference, rel=1e-13, abs=1e-15)
