"""Reports (report/format.py, report/motion.py): numbers leave strokeopt here, NaN never does."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from strokeopt.report.format import format_table, format_value, to_json
from strokeopt.report.motion import kinematics_summary, kinematics_text, plot_kinematics


def test_json_refuses_nan_and_names_the_field():
    with pytest.raises(ValueError, match=r"moves\[1\]\.a_max"):
        to_json({"moves": [{"a_max": 1.0}, {"a_max": float("nan")}]})


def test_json_writes_infinity_as_null_and_numpy_as_plain_numbers():
    data = json.loads(to_json({"jerk": math.inf, "n": np.int64(3), "ok": np.bool_(True), "x": np.float64(0.5)}))
    assert data == {"jerk": None, "n": 3, "ok": True, "x": 0.5}


@pytest.mark.parametrize("value, text", [
    (None, "-"), (True, "yes"), (False, "no"), (3, "3"), (0.0, "0"), (math.inf, "unbounded"),
    (1.23456, "1.235"), (270.81, "270.8"), (1160514.0, "1.161e+06"), (0.00012, "1.200e-04"),
])
def test_format_value(value, text):
    assert format_value(value) == text


def test_format_table_aligns_columns_under_their_headers():
    text = format_table([{"a": 1.5, "b": "x"}, {"a": 10.25, "b": None}], [("a", "a mm"), ("b", "name")], title="T")
    lines = text.splitlines()
    assert lines[0] == "T"
    assert len({len(line) for line in lines[1:]}) == 1  # every row as wide as the header
    assert lines[1].split() == ["a", "mm", "name"]
    assert lines[-1].split() == ["10.250", "-"]  # one format per column: 1.500 above it


def test_kinematics_summary_and_text(reference):
    summary = kinematics_summary(reference, reference.stroke(500), 500)
    assert [m["index"] for m in summary["moves"]] == [1, 2, 3]
    assert summary["cycle_time_s"] == pytest.approx(0.24)
    text = kinematics_text(summary)
    assert "500 spm" in text and "modified_sine" in text.replace(" ", "_").lower()
    json.loads(to_json(summary))  # no NaN anywhere


def test_kinematics_figure_is_written(reference, tmp_path):
    path = tmp_path / "k.png"
    fig = plot_kinematics(reference, [reference.stroke(500)], 500, path)
    assert path.stat().st_size > 10_000
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert len(labels) >= 3 and all(labels)  # position, velocity, acceleration (and jerk), each labelled
