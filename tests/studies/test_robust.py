"""The tolerance study (strokeopt robust): sampled machines judged with the design's stroke, reproducible,
the same numbers as the full simulation of each sampled machine, and bad tolerances refused in one line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from strokeopt.cli.main import main
from strokeopt.studies.robust import parse_tolerance, wilson_interval

REFERENCE = Path(__file__).resolve().parents[2] / "problems" / "deco2000_needle_bar.toml"
K2 = "model.springs.k2.stiffness_N_m"


@pytest.mark.parametrize("text, words", [
    ("model.springs.k9.stiffness_N_m=±10%", "no such field"),
    ("model.spring.k2.stiffness_N_m=±10%", "deco2000_needle_bar.toml (did you mean 'springs'?)"),
    ("drive.load_forces[0].x=±10%", "no element 0 (there are 1, counted from 1)"),   # arrays count from 1
    ("drive.load_forces[9].x=±10%", "no element 9 (there are 1) in"),
    ("problem.name=±10%", "not a number"),
    (f"{K2}=±0%", "must be positive"),
    (f"{K2}=±-5%", "the scatter must be positive, got -5"),
    (f"{K2}=±95%", "beyond ±90 %"),
    (f"{K2}=±2000", "reaches -1100, which the problem refuses"),  # a negative spring rate: outside its range
    (f"{K2}=10%", "expected FIELD"),
    # every sample had the design's rate: a yield for a scatter never simulated
    ("machine.spm=±10%", "[machine] is the design's"),
    ("timing.intervals[1].span_deg=±1", "[timing] is the design's"),
    ("design.handover_accuracy_mm=±10%", "[design] is the design's"),
    (f"{K2}=±1e-300", "changes no value of 900"),  # as 0 %: every sample the nominal machine
])
def test_bad_tolerances_are_refused(capsys, text, words):
    assert main(["robust", str(REFERENCE), "--tolerance", text, "--samples", "8", "--workers", "1",
                 "--plot", "none"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--tolerance" in err[0] and words in err[0]


def test_a_field_given_two_tolerances_is_refused_before_any_work(capsys):
    assert main(["robust", str(REFERENCE), "--tolerance", f"{K2}=±10%", "--tolerance", f"{K2}=±5%", "--samples", "8",
                 "--workers", "1", "--plot", "none"]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert err == [f"strokeopt: error: --tolerance: {K2} is given twice ({K2} = 900 ±10 % (uniform) and {K2} = 900 "
                   "±5 % (uniform)): give each field one tolerance"]
    assert "objective" not in captured.out  # refused before the design was solved


@pytest.mark.parametrize("option, words", [(["--samples", "3"], "--samples: must lie in [8, 100000]"),
                                           (["--samples", "x"], "--samples: expected a whole number"),
                                           (["--seed", "-1"], "--seed: must lie in")])
def test_bad_study_options(capsys, option, words):
    assert main(["robust", str(REFERENCE), "--tolerance", f"{K2}=±10%", *option, "--plot", "none"]) == 2
    assert words in capsys.readouterr().err


def test_tolerance_values_and_the_wilson_interval(reference):
    t = parse_tolerance(f"{K2}=±10%", reference)
    assert t.bounds == pytest.approx((810.0, 990.0)) and t.value(0.5) == pytest.approx(900.0)
    n = parse_tolerance("model.contacts.c32.gap_mm=±0.3:normal", reference)
    assert n.value(0.5) == pytest.approx(7.4) and 7.1 <= n.value(1e-9) < n.value(0.99) <= 7.7
    lo, hi = wilson_interval(95, 100)  # the textbook value for 95 of 100: 0.888 to 0.978
    assert (lo, hi) == pytest.approx((0.8882, 0.9785), abs=5e-4)


@pytest.mark.slow  # a solve at 600 spm, two studies of 8 samples and three verifications
def test_study_is_reproducible_and_matches_the_full_simulation(tmp_path, capsys):
    out = tmp_path / "d"
    assert main(["solve", str(REFERENCE), "--spm", "600", "--out", str(out), "--plot", "none", "--json"]) == 0
    capsys.readouterr()
    argv = ["robust", str(REFERENCE), "--design", str(out / "design.json"), "--tolerance", f"{K2}=±10%",
            "--samples", "8", "--seed", "3", "--workers", "1", "--json", "--plot", "none"]
    assert main(argv) == 0
    first = json.loads(capsys.readouterr().out)
    assert main(argv) == 0
    again = json.loads(capsys.readouterr().out)
    assert first["rows"] == again["rows"] and first["yield"] == again["yield"]  # same seed, same numbers
    # the yield counts what is judged: the lag and impact velocity (no [design.contact] limits) are named beside it
    # with their range over the samples; set the limits and they are judged (and counted)
    assert first["criteria"] == ["handover accuracy", "premature release", "peak_torque", "rms_torque"]
    named = {c["criterion"]: c for c in first["not_judged"]}
    assert set(named) == {"lag", "impact velocity"}
    lags = [r["max_lag_mm"] for r in first["rows"]]
    assert (named["lag"]["low"], named["lag"]["high"], named["lag"]["samples"]) == (min(lags), max(lags), 8)
    assert named["impact velocity"]["limit_field"] == "design.contact.impact_velocity_max_m_s"
    limits = ["--set", f"design.contact.lag_max_mm={min(lags) + 0.5 * (max(lags) - min(lags))!r}",
              "--set", "design.contact.impact_velocity_max_m_s=5.0"]
    assert main([a for a in argv if a != "--json"] + limits) == 0
    text = capsys.readouterr().out
    assert "not judged" not in text and "failed: lag in " in text
    assert len(first["rows"]) == 8 and {r[K2] for r in first["rows"]} <= set(r[K2] for r in again["rows"])
    # three samples re-simulated as a user would: verify the design with the sampled k2 set
    for row in first["rows"][:3]:
        assert main(["verify", str(REFERENCE), "--design", str(out / "design.json"), "--set",
                     f"{K2}={row[K2]!r}", "--json", "--plot", "none"]) in (0, 1)
        sim = json.loads(capsys.readouterr().out)
        assert row["impact_velocity_m_s"] == pytest.approx(abs(sim["impact_velocity_m_s"]), rel=1e-9)
        assert row["max_lag_mm"] == pytest.approx(sim["max_lag_mm"], rel=1e-9)
    # k2 is what moves the lag and the impact (digest A.6): rank correlations -1 and +1 over the sample
    (sens,) = first["sensitivity"]
    assert sens["max_lag_mm"] == pytest.approx(-1.0) and sens["impact_velocity_m_s"] == pytest.approx(1.0)
