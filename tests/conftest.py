"""Fixtures for every test: symbolic derivations are kept in a folder of the session's own
(:mod:`problems.derivation_cache`), never in the user's cache; the eulertop commands tests run
as processes inherit it."""

from __future__ import annotations

import os

import pytest

from problems.derivation_cache import CACHE_ENV


@pytest.fixture(scope="session", autouse=True)
def derivations_kept_for_the_session(tmp_path_factory):
    folder = tmp_path_factory.mktemp("derivations")
    before = os.environ.get(CACHE_ENV)
    os.environ[CACHE_ENV] = str(folder)
    yield folder
    if before is None:
        os.environ.pop(CACHE_ENV, None)
    else:
        os.environ[CACHE_ENV] = before
