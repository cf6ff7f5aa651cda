"""Symbolic derivations kept between runs (problems/derivation_cache.py): read back only when
their digest is the same and the file is the user's alone; the families that keep them give the
same answers either way."""

from __future__ import annotations

import json
import os
import stat
import types

import pytest
import sympy as sp

from problems import derivation_cache
from problems.derivation_cache import CACHE_ENV, kept
from problems.templates import euler_kinetic_energy, symbolic_derivation
from solver import symbolic
from solver.symbolic import SYMBOLS


class Derivation:
    """A derivation that counts its calls."""

    def __init__(self, value):
        self.value, self.calls = value, 0

    def __call__(self):
        self.calls += 1
        return self.value


VALUE = {"key": "I1*alpha_dot", "mistakes": [["swapped", "I3*alpha_dot", "I1 and I3 swapped"]]}


@pytest.fixture
def folder(tmp_path, monkeypatch):
    where = tmp_path / "kept"
    monkeypatch.setenv(CACHE_ENV, str(where))
    return where


@pytest.fixture
def source(tmp_path):
    """A module of its own file, standing for a family's source."""
    path = tmp_path / "family_source.py"
    path.write_text("K = 1\n")
    return types.SimpleNamespace(__file__=str(path))


def test_a_derivation_is_kept_and_read_back_without_deriving_again(folder, source):
    derive = Derivation(VALUE)
    assert kept("family.T", [source], derive) == VALUE
    assert kept("family.T", [source], derive) == VALUE
    assert derive.calls == 1
    (file,) = folder.iterdir()
    assert file.name.startswith("family.T-")
    assert stat.S_IMODE(file.stat().st_mode) == 0o600  # the user's alone
    assert stat.S_IMODE(folder.stat().st_mode) & 0o077 == 0


def test_a_changed_source_is_derived_again_and_replaces_the_old(folder, source):
    kept("family.T", [source], Derivation(VALUE))
    with open(source.__file__, "a") as f:
        f.write("K = 2\n")
    derive = Derivation({"key": "I3*alpha_dot", "mistakes": []})
    assert kept("family.T", [source], derive) == derive.value and derive.calls == 1
    assert len(list(folder.iterdir())) == 1


def test_another_name_is_kept_beside_it(folder, source):
    kept("family.T", [source], Derivation(VALUE))
    kept("family.T_other", [source], Derivation(VALUE))
    assert len(list(folder.iterdir())) == 2


def _planted(file, folder):
    """What another user might leave: a record with the right digest whose texts run code."""
    record = json.loads(file.read_text())
    record["value"] = {"key": "__import__('os').getcwd()", "mistakes": []}
    file.write_text(json.dumps(record))


def _group_writable(file, folder):
    _planted(file, folder)
    file.chmod(0o620)


def _world_writable_folder(file, folder):
    _planted(file, folder)
    folder.chmod(0o777)


def _someone_elses(file, folder):
    _planted(file, folder)


def _a_symbolic_link(file, folder):
    elsewhere = folder.parent / "elsewhere.json"
    file.rename(elsewhere)
    _planted(elsewhere, folder)
    file.symlink_to(elsewhere)


def _damaged(file, folder):
    file.write_text(file.read_text()[:40])


def _another_digest(file, folder):
    record = json.loads(file.read_text())
    record["digest"] = "0" * 64
    record["value"] = {"key": "x", "mistakes": []}
    file.write_text(json.dumps(record))


@pytest.mark.parametrize("spoil", [_group_writable, _world_writable_folder, _someone_elses,
                                   _a_symbolic_link, _damaged, _another_digest])
def test_a_file_not_the_users_alone_or_not_this_digest_is_never_read(folder, source, spoil,
                                                                      monkeypatch):
    kept("family.T", [source], Derivation(VALUE))
    (file,) = folder.iterdir()
    spoil(file, folder)
    if spoil is _someone_elses:  # the file and folder then belong to another user
        real = os.geteuid()
        monkeypatch.setattr(derivation_cache.os, "geteuid", lambda: real + 1)
    derive = Derivation(VALUE)
    assert kept("family.T", [source], derive) == VALUE
    assert derive.calls == 1


def test_no_folder_to_keep_in_is_only_a_derivation(tmp_path, monkeypatch, source):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    monkeypatch.setenv(CACHE_ENV, str(blocker / "kept"))  # below a file: mkdir fails
    derive = Derivation(VALUE)
    assert kept("family.T", [source], derive) == VALUE
    assert kept("family.T", [source], derive) == VALUE and derive.calls == 2


def test_off_keeps_nothing(tmp_path, monkeypatch, source):
    monkeypatch.setenv(CACHE_ENV, "off")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    derive = Derivation(VALUE)
    kept("family.T", [source], derive)
    kept("family.T", [source], derive)
    assert derive.calls == 2 and not (tmp_path / "cache").exists()


def test_the_default_folder_is_the_users_cache(tmp_path, monkeypatch):
    monkeypatch.delenv(CACHE_ENV)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert derivation_cache.cache_folder() == tmp_path / "eulertop" / "derivations"
    monkeypatch.delenv("XDG_CACHE_HOME")
    monkeypatch.setenv("HOME", str(tmp_path / "home"))
    assert derivation_cache.cache_folder() == tmp_path / "home" / ".cache" / "eulertop" / \
        "derivations"


# --------------------------------------------------------------------------------------------
# The families that keep their derivations


QUANTITIES = range(len(symbolic_derivation.QUANTITIES))


@pytest.mark.parametrize("index", QUANTITIES,
                         ids=[q.name for q in symbolic_derivation.QUANTITIES])
def test_each_derived_expression_reads_back_from_its_text_unchanged(index):
    """What makes a kept derivation give what a fresh one gives: every expression, parsed from
    its text, is the same sympy expression (so its lambdify'd function is the same code)."""
    q = symbolic_derivation.QUANTITIES[index]
    key = q.derive()
    expressions = [key, *(e for _, e, _ in q.mistakes(key))]
    for expression in expressions:
        assert symbolic_derivation._parsed(str(expression)) == expression


def test_the_kinetic_energy_texts_read_back_unchanged():
    texts = euler_kinetic_energy._derived_texts()
    symmetric = euler_kinetic_energy._symmetric_top_energy()
    local = dict(SYMBOLS)
    assert sp.parse_expr(texts["key"], local_dict=local) == symmetric
    assert str(symmetric) == texts["key"]


@pytest.fixture
def fresh_families():
    """The two families' per-process results forgotten before and after the test."""
    for f in (symbolic_derivation._compiled, euler_kinetic_energy._expression_answer):
        f.cache_clear()
    yield
    for f in (symbolic_derivation._compiled, euler_kinetic_energy._expression_answer):
        f.cache_clear()


def test_kept_derivations_give_the_answers_and_functions_fresh_ones_give(folder, monkeypatch,
                                                                        fresh_families):
    derived = [symbolic_derivation._compiled(i) for i in QUANTITIES]
    energy = euler_kinetic_energy._expression_answer()
    assert len(list(folder.iterdir())) == len(QUANTITIES) + 1

    def underived(*args):
        raise AssertionError("derived again although kept")

    monkeypatch.setattr(symbolic_derivation, "_derived_texts", underived)
    monkeypatch.setattr(euler_kinetic_energy, "_derived_texts", underived)
    for f in (symbolic_derivation._compiled, euler_kinetic_energy._expression_answer):
        f.cache_clear()
    read_back = [symbolic_derivation._compiled(i) for i in QUANTITIES]
    assert euler_kinetic_energy._expression_answer() == energy
    point = {"I1": 1.3, "I3": 0.7, "Mgl": 2.1, "beta": 0.9, "alpha_dot": 0.4, "beta_dot": 0.3,
             "gamma_dot": 5.2, "p_alpha": 1.1, "p_gamma": 3.4}
    for q, before, after in zip(symbolic_derivation.QUANTITIES, derived, read_back, strict=True):
        assert after.expression == before.expression
        args = [point[n] for n in q.symbols]
        assert after.key(*args) == before.key(*args)
        assert [f(*args) for _, f, _ in after.mistakes] == \
            [f(*args) for _, f, _ in before.mistakes]


def test_the_digest_covers_the_solver_sources(source):
    """A derivation depends on solver.symbolic (and what it imports), so every solver module
    is part of the digest, beside the family's own source."""
    assert os.path.samefile(symbolic.__file__,
                            next(p for p in derivation_cache._source_files([source])
                                 if p.name == "symbolic.py"))
