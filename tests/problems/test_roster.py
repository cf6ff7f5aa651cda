"""Roster reading: good files in their usual shapes, and every bad input named precisely."""

from __future__ import annotations

import pytest

from problems.roster import Roster, RosterError, id_problem, read_roster


def test_columns_rows_and_order_are_kept(write_roster):
    roster = read_roster(write_roster("id,name,email\nzed,Zed,z@x\nann,Ann,a@x\n"))
    assert roster.columns == ("id", "name", "email")
    assert roster.ids == ("zed", "ann")
    assert roster.rows[1] == {"id": "ann", "name": "Ann", "email": "a@x"}


@pytest.mark.parametrize(
    ("content", "ids", "columns"),
    [
        ("\ufeffid,name\nann,Ann\n", ("ann",), ("id", "name")),  # Excel's byte-order mark
        (" ID ,name\r\n ann ,Ann\r\n\r\nbob,Bob\r\n", ("ann", "bob"), ("id", "name")),
        ("name,id\nAnn\n", None, None),  # short row: padded, then its empty id is refused
        ('id,note\nann,"two\nlines"\nbob,x\n', ("ann", "bob"), ("id", "note")),
        ("id\nann.lee@uni.example\nb_2-x\n", ("ann.lee@uni.example", "b_2-x"), ("id",)),
    ],
)
def test_usual_csv_shapes(write_roster, content, ids, columns):
    path = write_roster(content)
    if ids is None:
        with pytest.raises(RosterError, match="line 2, column 'id': empty id"):
            read_roster(path)
        return
    roster = read_roster(path)
    assert roster.ids == ids
    assert roster.columns == columns
    assert all(set(row) == set(columns) for row in roster.rows)


def test_roster_round_trips_through_dict(write_roster):
    roster = read_roster(write_roster("id,name\nann,Ann\nbob,\n"))
    assert Roster.from_dict(roster.to_dict()) == roster


@pytest.mark.parametrize(
    ("content", "fragments"),
    [
        ("", ["roster is empty"]),
        ("id,name\n", ["header but no students"]),
        ("\n\n", ["roster is empty"]),  # csv sees no header row at all
        ("name,email\nann,a@x\n", ["line 1", "no column 'id'", "'name', 'email'"]),
        ("id,name,id\nann,A,b\n", ["line 1", "'id' appears 2 times"]),
        ("id,name\nann,Ann,extra\n", ["line 2", "3 fields", "2 columns"]),
        ("id,name\nann,A\nbob,B\nann,C\n", ["duplicate ids", "'ann' (line 2)", "'ann' (line 4)"]),
        ("id\nAnn\nbob\nann\n", ["duplicate ids", "'Ann' (line 2)", "'ann' (line 4)"]),
        ("id,name\nann,A\n,B\n", ["line 3, column 'id'", "empty id"]),
        ("id\nann\n../x\n", ["line 3", "'../x'", "path"]),
        ("id\na/b\n", ["line 2", "'a/b'", "path"]),
        ("id\na\\b\n", ["line 2", "path"]),
        ("id\n.\n", ["line 2", "path"]),
        ("id\n.hidden\n", ["line 2", "'.hidden'", "must start with a letter or digit"]),
        ("id\n-rf\n", ["line 2", "'-rf'"]),
        ("id\nann.\n", ["line 2", "not ending with '.'"]),
        ("id\nan\x01n\n", ["line 2", "'an\\x01n'"]),
        ("id\nann lee\n", ["line 2", "'ann lee'"]),
        ("id\nmüller\n", ["line 2", "ASCII"]),
        ("id\n" + "a" * 101 + "\n", ["line 2", "longer than 100"]),
    ],
)
def test_bad_rosters_are_named_precisely(write_roster, content, fragments):
    path = write_roster(content)
    with pytest.raises(RosterError) as info:
        read_roster(path)
    message = str(info.value)
    assert str(path) in message
    for fragment in fragments:
        assert fragment in message


def test_non_utf8_names_the_line(write_roster):
    path = write_roster("id,name\nann,Ann\nbob,J\xfcrgen\n".encode("latin-1"))
    with pytest.raises(RosterError, match=r"line 3: not UTF-8 \(byte 0xfc\)"):
        read_roster(path)


@pytest.mark.parametrize("what", ["missing", "folder"])
def test_unreadable_file(tmp_path, what):
    path = tmp_path / "roster.csv"
    if what == "folder":
        path.mkdir()
    with pytest.raises(RosterError, match="cannot read the roster"):
        read_roster(path)


@pytest.mark.parametrize("good", ["a", "7", "ann.lee", "a_b-c", "x@y.z", "A1", "a..b", "a" * 100])
def test_good_ids(good):
    assert id_problem(good) is None


@pytest.mark.parametrize("bad", ["", ".", "..", "../x", "a/b", "_a", "a\nb", "a\tb", "a.", "é"])
def test_bad_ids(bad):
    assert id_problem(bad)
