"""One Canvas class through the real commands and real kernels: export → generate → zip →
grade → import file. Every other LMS test grades without kernels."""

from __future__ import annotations

import json

import pytest

from eulertop.cli import main
from tests.grader.lms.conftest import read_csv
from tests.grader.lms.exports import (
    CLASS,
    MULLER,
    WEI,
    canvas_file_name,
    canvas_gradebook,
    notebook,
    write_zip,
)


@pytest.mark.slow
def test_a_canvas_class_from_its_own_exports_to_its_import_file(tmp_path, capsys):
    (tmp_path / "gradebook.csv").write_text(canvas_gradebook(), encoding="utf-8")
    hw = tmp_path / "HW"
    assert main(["generate", "--roster", str(tmp_path / "gradebook.csv"), "--out", str(hw),
                 "--problems", "inertia_tensor", "--seed", "21", "--title", "HW 1"]) == 0
    download = write_zip(tmp_path / "submissions.zip", {
        canvas_file_name(MULLER, 501, "hw1.ipynb"): notebook(hw, "jmuller"),
        canvas_file_name(WEI, 502, "hw1.ipynb", late=True): notebook(hw, "4505", right=False),
        ".DS_Store": b"\0",
    })
    code = main(["grade", str(hw), str(download), "--jobs", "2", "--timeout", "90"])
    err = capsys.readouterr().err
    assert code == 0, err
    records = {sid: json.loads((hw / "graded" / "results" / f"{sid}.json").read_text())
               for sid in ("jmuller", "4505")}
    assert records["jmuller"]["execution"]["status"] == "ok"
    assert records["jmuller"]["points"] == records["jmuller"]["max_points"] > 0
    assert records["4505"]["points"] == 0
    assert "4505: submitted late" in err
    assert main(["export", str(hw), "--to", "canvas", "--assignment-id", "77001"]) == 0
    table = read_csv(hw / "graded" / "canvas-import.csv")
    full = f"{records['jmuller']['max_points']:.10g}"
    assert table[0][-1] == "HW 1 (77001)" and table[1] == ["Points Possible", "", "", "", "",
                                                         full]
    assert {r[1]: r[5] for r in table[2:]} == {
        str(p.canvas): {MULLER: full, WEI: "0"}.get(p, "") for p in CLASS}
