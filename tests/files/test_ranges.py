"""`--spm` values and START:STOP:STEP ranges (io/ranges.py), shared by `simulate` and `solve`."""

from __future__ import annotations

import pytest

from strokeopt import ProblemError
from strokeopt.cli.main import main
from strokeopt.files.ranges import parse_spm_range


@pytest.mark.parametrize("text, values", [
    ("600", [600.0]),
    ("300:400:50", [300.0, 350.0, 400.0]),
    ("300:420:50", [300.0, 350.0, 400.0]),  # STOP is never passed
    ("30:42:6", [30.0, 36.0, 42.0]),
    ("500:500:10", [500.0]),
    ("1.5:1.8:0.1", [1.5, 1.6, 1.7, 1.8]),  # round-off does not drop STOP
])
def test_values(text, values):
    assert parse_spm_range(text) == pytest.approx(values)


@pytest.mark.parametrize("text, words", [
    ("fast", "expected SPM or START:STOP:STEP"),
    ("300:400", "expected SPM or START:STOP:STEP"),
    ("300:x:10", "expected SPM or START:STOP:STEP"),
    ("300:200:10", "STEP > 0 and STOP >= START"),
    ("300:400:0", "STEP > 0 and STOP >= START"),
    ("300:400:-10", "STEP > 0 and STOP >= START"),
    ("0", "0 spm is outside the plausible range [1, 20000]"),
    ("-300:400:50", "-300 spm is outside the plausible range [1, 20000]"),
    ("300:inf:50", "every number must be finite"),
    ("nan", "every number must be finite"),
    # issue 14: a MemoryError, a numpy ValueError and a sweep of 1.9 million design solves before
    ("400:1e9:1", "1e+09 spm is outside the plausible range"),
    ("400:inf:50", "every number must be finite"),
    ("nan:900:50", "every number must be finite"),
    ("400:900:inf", "every number must be finite"),
    ("1:20000:1", "20000 stitch rates, more than 2000"),
    ("1e-12", "outside the plausible range"),
])
def test_refused(text, words):
    with pytest.raises(ProblemError, match="--spm") as exc:
        parse_spm_range(text)
    assert words in str(exc.value)


@pytest.mark.parametrize("command", ["simulate", "solve"])
def test_both_commands_refuse_alike(capsys, reference_path, command):
    assert main([command, str(reference_path), "--spm", "900:400:50", "--plot", "none"]) == 2
    err = capsys.readouterr().err
    assert "--spm" in err and "STEP > 0 and STOP >= START" in err and err.count("\n") == 1
