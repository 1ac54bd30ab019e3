"""A stroke must fit the contact model's gaps and stops (issue 22, "strokes that do not fit the model's gaps and
stops"): the travel the driven body has before a chain of contacts presses it into the frame is derived from
[model] (contact/travel.py), and a problem whose dwells or handover position lie beyond it is refused on read,
in one line naming the file, the interval's field and the chain."""

from __future__ import annotations

import json

import pytest

from strokeopt import ProblemError, load_problem
from strokeopt.cli.main import main
from strokeopt.contact.travel import travel_range

from conftest import ROOT

X1000 = ["timing.start_position_mm=32000", "timing.intervals[2].stroke_mm=32000",
         "timing.intervals[4].stroke_mm=35000", "timing.intervals[5].stroke_mm=3000"]


def _sets(overrides):
    return [a for o in overrides for a in ("--set", o)]


def test_the_reference_shell_meets_the_frame_34_mm_below_its_upper_dwell(reference):
    # gap P 3.6 + gap N 7.4 + gap H 23 mm: shell -> cage (c13) -> control (c32) -> frame (pad); nothing stops it
    # upward. The stroke takes it 32 mm down: 2 mm to spare
    (ahead, chain), (behind, back) = travel_range(reference.model)
    assert ahead == pytest.approx(0.034) and chain == ["c13", "c32", "pad"]
    assert behind == float("inf") and back == []


def test_the_elastic_chain_has_no_stop():
    p = load_problem(ROOT / "problems" / "knitting_stitch_density.toml")
    assert travel_range(p.model) == ((float("inf"), []), (float("inf"), []))


def test_every_stroke_x1000_is_refused_on_read(reference_path, capsys):
    # the repro: a 32 m move simulated "ok" with a 1.6e10 N pad force and a 78.7 m/s impact
    code = main(["simulate", str(reference_path), *_sets(X1000), "--plot", "none"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert err.startswith(f"strokeopt: error: {reference_path}: timing.intervals[2].stroke_mm: 'move 1' takes the "
                          "driven shell 32000 mm"), err
    assert "beyond the 34 mm its contacts leave it (c13 3.6 mm + c32 7.4 mm + pad 23 mm" in err
    code = main(["simulate", str(reference_path), *_sets(X1000), "--plot", "none", "--json"])
    data = json.loads(capsys.readouterr().out)
    assert code == 2 and data["status"] == "bad input" and "timing.intervals[2].stroke_mm" in data["message"]


@pytest.mark.parametrize("overrides, field, words", [
    # gap P closed: the shell presses the cage, the cage the control member, the control member the pad at 30.4 mm
    (["model.contacts.c13.gap_mm=0"], "timing.intervals[2].stroke_mm", "beyond the 30.4 mm"),
    # the pad 8 mm higher: the chain closes at 26 mm
    (["model.contacts.pad.gap_mm=15"], "timing.intervals[2].stroke_mm", "beyond the 26 mm"),
    # a longer first move: 35 mm down
    (["timing.start_position_mm=35", "timing.intervals[2].stroke_mm=35", "timing.intervals[4].stroke_mm=38"],
     "timing.intervals[2].stroke_mm", "takes the driven shell 35 mm"),
])
def test_a_stroke_past_the_chain_to_the_frame_is_refused(reference_path, overrides, field, words):
    with pytest.raises(ProblemError) as exc:
        load_problem(reference_path, overrides)
    assert exc.value.field == field and words in str(exc.value)


def test_a_chain_that_reaches_exactly_the_stroke_is_accepted(reference_path):
    # gap P 0 and gap N 9 mm: 0 + 9 + 23 = 32 mm, the lower dwell touches the chain with no force
    p = load_problem(reference_path, ["model.contacts.c13.gap_mm=0", "model.contacts.c32.gap_mm=9"])
    assert travel_range(p.model)[0][0] == pytest.approx(0.032)


def test_a_stop_behind_the_driven_body_bounds_its_travel_backward(write_problem):
    # a stop above the shell 2 mm over its upper dwell: move 2 takes it 3 mm above (35 mm up from 0)
    path = write_problem(lambda t: t.replace("[model.events]", '[model.contacts.top]\nbodies = ["frame", "shell"]\n'
                                                                "gap_mm = 2.0\nstiffness_N_m = 1e9\n\n[model.events]"))
    with pytest.raises(ProblemError) as exc:
        load_problem(path)
    assert exc.value.field == "timing.intervals[4].stroke_mm"
    assert "'move 2' takes the driven shell 3 mm" in str(exc.value) and "beyond the 2 mm" in str(exc.value)
    assert "(top 2 mm of gap to the frame" in str(exc.value)
    wide = write_problem(lambda t: t.replace("[model.events]", '[model.contacts.top]\nbodies = ["frame", "shell"]\n'
                                                                "gap_mm = 3.0\nstiffness_N_m = 1e9\n\n[model.events]"),
                         "wide.toml")
    assert travel_range(load_problem(wide).model)[1] == (pytest.approx(0.003), ["top"])
