"""Property tests of the linkage file and of the tolerance study's options (issue 22: "the linkage and
tolerance-study inputs as they land").

* A linkage file (the loom's six-bar) mutated one to three times (a number scaled by 10^k or its sign flipped, a
  value of another type, a key deleted or misspelt, an array truncated) through ``strokeopt linkage FILE --json``
  (the analysis, not the synthesis: a fraction of a second).
* ``strokeopt robust`` with its options drawn from valid and invalid values, at least one invalid in every case
  (a tolerance text, --samples, --seed, --workers, --spm), so each is refused before any solve or sample.

The property, for every case: no traceback; exit 0, 1 or 2 only; a refusal (2) is one error line; under --json
one JSON object with a status, a failure object with its message when the command fails, no NaN or null where a
number is expected. Derandomized: the same cases on every run."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from test_property_design_files import _one_answer, _run
from input_cases import field_paths, mutated
from test_property_inputs import SWAPS, to_toml

from conftest import REFERENCE, ROOT

LOOM = ROOT / "problems" / "loom_beatup_sixbar.toml"
LOOM_DATA = tomllib.loads(LOOM.read_text(encoding="utf-8"))


#: Every field of the file, [synthesis] and a link's cg_on_line included.
LOOM_PATHS = sorted(field_paths(LOOM_DATA), key=repr)


def mutated_linkage():
    return mutated(LOOM_DATA, LOOM_PATHS, scales=(-300, -30, -6, -3, -1, 1, 3, 6, 30, 300), swaps=SWAPS,
                   whole_numbers=True)


def test_the_generator_writes_the_linkage_file_back():
    # the TOML writer is faithful for this file too: unmutated, it reads back unchanged
    assert tomllib.loads(to_toml(LOOM_DATA)) == LOOM_DATA


@pytest.mark.slow  # 300 mutated linkage files, each analysed
@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(data=mutated_linkage())
def test_any_linkage_file_is_answered_or_refused_in_one_line(tmp_path, data):
    path = tmp_path / "mutant.toml"
    path.write_text(to_toml(data), encoding="utf-8")
    code, out, err = _run(["linkage", str(path), "--json", "--plot", "none"])
    _one_answer(code, out, err)
    if code == 2:  # refused naming the file
        assert f"{path}: " in json.loads(out)["message"], out


def _sley(d) -> dict:
    return next(link for link in d["transmission"]["links"] if "cg_on_line" in link)


@pytest.mark.parametrize("edit, field", [
    (lambda d: d["synthesis"]["fixed_lengths"][0].update(length_mm="abc"), "synthesis.fixed_lengths"),
    (lambda d: d["synthesis"]["fixed_lengths"][0].pop("joints"), "synthesis.fixed_lengths"),
    (lambda d: d["synthesis"]["fixed_angles"][0].update(lines=True), "synthesis.fixed_angles"),
    (lambda d: d["synthesis"]["fixed_angles"][0].pop("angle_deg"), "synthesis.fixed_angles"),
    (lambda d: d["synthesis"].update(fixed_joints=True), "synthesis.fixed_joints"),
    (lambda d: d["synthesis"].update(fixed_angles=True), "synthesis.fixed_angles"),
    (lambda d: _sley(d).update(cg_on_line=_sley(d)["cg_on_line"][:1]), "cg_on_line"),
], ids=["length a text", "joints missing", "lines a boolean", "angle missing", "fixed joints a boolean",
        "fixed angles a boolean", "cg_on_line of one joint"])
def test_a_damaged_synthesis_or_cg_field_is_refused_in_one_line(tmp_path, edit, field):
    data = json.loads(json.dumps(LOOM_DATA))
    edit(data)
    path = tmp_path / "damaged.toml"
    path.write_text(to_toml(data), encoding="utf-8")
    code, out, err = _run(["linkage", str(path), "--json", "--plot", "none"])
    assert code == 2 and f"{path}: " in json.loads(out)["message"] and field in json.loads(out)["message"], out


# ------------------------------------------------------------------------------------------------ robust

GOOD = {
    "tolerance": ["model.springs.k2.stiffness_N_m=±10%", "model.contacts.c32.gap_mm=±0.1:normal"],
    "samples": ["8", "200"],
    "seed": ["0", "42"],
    "workers": ["1"],
    "spm": ["500", "600"],
}
BAD = {
    "tolerance": ["model.springs.k2.stiffness_N_m=±200%", "model.springs.k2.stiffness_N_m=±0%",
                  "model.springs.k2.stiffness_N_m=±abc", "model.springs.k2.stiffness_N_m=10%", "=±10%", "",
                  "nope.field=±1", "problem.name=±1", "model.contacts.c32.gap_mm=±8",
                  # gap P down to 0 mm: the shell would press the chain into the pad (contact/travel.py)
                  "model.contacts.c13.gap_mm=±3.6", "model.springs.k2.stiffness_N_m=±10%:weird",
                  "machine.spm=±1e9", "model.springs.k2.stiffness_N_m=±nan", "model.springs.k2.stiffness_N_m=±inf"],
    "samples": ["0", "7", "100001", "1e9", "abc", "", "-1", "8.5", "nan"],
    "seed": ["-1", "abc", "4294967296", "1.5", ""],
    "workers": ["0", "-1", "abc", "inf", "1e9"],
    "spm": ["abc", "0", "1e9", "nan", ""],
}


@st.composite
def robust_options(draw) -> list[str]:
    """Options of ``strokeopt robust``: each drawn valid or absent, then one of them made invalid."""
    chosen = {k: draw(st.sampled_from([None, *v])) for k, v in GOOD.items()}
    bad = draw(st.sampled_from(sorted(BAD)))
    chosen[bad] = draw(st.sampled_from(BAD[bad]))
    argv = []
    for key, value in chosen.items():
        if value is None:
            continue
        argv.append(f"--{key}={value}")
        if key == "tolerance" and draw(st.booleans()):  # a second tolerance, valid
            argv.append(f"--tolerance={GOOD['tolerance'][0]}")
    return argv


@pytest.mark.slow  # 300 command lines, each reading the problem file (and a design file)
@settings(max_examples=300, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(options=robust_options(), design=st.booleans(), as_json=st.sampled_from([True, True, True, False]))
def test_robust_options_outside_their_ranges_are_refused_in_one_line(robust_design, options, design, as_json):
    # every case has an option outside its range or unreadable: refused before any solve or sample
    argv = ["robust", str(REFERENCE), *options, "--plot", "none"]
    argv += ["--design", str(robust_design)] if design else []
    code, out, err = _run(argv + (["--json"] if as_json else []))
    assert code == 2, (options, err)
    _one_answer(code, out, err, json_mode=as_json)


@pytest.fixture(scope="module")
def robust_design(tmp_path_factory) -> Path:
    """A design file of the reference problem (robust --design reads it; no case gets as far as judging it)."""
    out = tmp_path_factory.mktemp("robust")
    code, _, err = _run(["solve", str(REFERENCE), "--motor", "055U2B30", "--pulley-teeth", "28", "--out", str(out),
                         "--json", "--plot", "none"])
    assert code == 0, err
    return out / "design.json"
