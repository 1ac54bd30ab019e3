"""Shared fixtures: the reference problem, and its design solved once per run (``reference_verified``,
``reference_written``) for every test that reads the reference design rather than making it.

The edit loop is ``pytest -m "not slow"``; CI runs everything (the ``slow`` marker, pyproject.toml)."""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

import pytest

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "problems" / "deco2000_needle_bar.toml"


def stated_k2(text: str) -> str:
    """The reference's text with the drive's k2 load force stated by its own numbers instead of
    ``model_spring = "k2"`` and ``model_contact = "pad"`` (for variants without [model], or that state k2
    twice on purpose): 15.39 N preload, 900 N/m, from 32 - 23 = 9 mm."""
    import re

    text = re.sub(r'model_spring = "k2"[^\n]*\n', "preload_N = 15.39\nstiffness_N_m = 900\n", text)
    return re.sub(r'model_contact = "pad"[^\n]*\n( {2,}#[^\n]*\n)*', "contact_position_mm = 9.0\n", text)


@pytest.fixture(scope="session")
def reference_path() -> Path:
    return REFERENCE


@pytest.fixture(scope="session")
def reference():
    from strokeopt import load_problem

    return load_problem(REFERENCE)


class Written(NamedTuple):
    """A verified design written as ``strokeopt solve --out DIR --json`` writes it."""

    out: Path  # DIR: design.json, cam_table.csv, cam_table.txt, report.html
    summary: dict  # the JSON ``solve --json`` prints for it (the drive block included)

    @property
    def design_json(self) -> Path:
        return self.out / "design.json"


def _write_verified(verified, out: Path, spec=None, report: bool = True) -> Written:
    """Write ``verified`` (a :class:`strokeopt.VerifiedDesign` of a problem solved without command-line
    drive options) as ``strokeopt solve --out OUT --json`` does: the ``solve --json`` report, design.json with
    its comparison, drive, verdict and unjudged criteria, the cam tables (as ``spec``, a
    :class:`strokeopt.files.design_file.CamTableSpec`, says: the cam table options) and, with ``report``,
    report.html."""
    import json

    from strokeopt.cli.common import drive_used
    from strokeopt.files.design_file import write_design
    from strokeopt.io.plain import to_json
    from strokeopt.report.design_report import gather, write_report

    design, problem = verified.design, verified.problem
    chosen = drive_used(None, problem, design.motor, design.pulley_teeth)
    if problem.design is not None and (problem.design.motor_choice != "fixed" or problem.design.pulley != "fixed"):
        chosen["from"] = (f"the solve's choice: design.motor_choice = {problem.design.motor_choice}, design.pulley "
                          f"= {problem.design.pulley}")
    summary = {**verified.summary(), "drive": chosen}
    write_design(design, out, spec=spec, extra={"comparison": verified.comparison, "drive": chosen,
                                                "verdict": verified.verdict, "not_judged": summary["not_judged"]})
    if report:
        write_report(gather(verified, summary), Path(out) / "report.html")
    return Written(Path(out), json.loads(to_json(summary)))


@pytest.fixture(scope="session")
def reference_verified():
    """The reference problem at its 500 spm solved once for the whole run through the library's verified
    pipeline (:func:`strokeopt.solve_verified`, the answer of ``strokeopt solve``): 055U2B30, 24 teeth,
    0.8596 N m, simulated in the servo loop and the release scene. Shared: read it, never change it."""
    from strokeopt import load_problem, solve_verified

    return solve_verified(load_problem(REFERENCE))


@pytest.fixture(scope="session")
def reference_written(reference_verified, tmp_path_factory) -> Written:
    """The reference design written once as ``strokeopt solve REFERENCE --out DIR --json`` writes it
    (design.json, the cam tables at 0.1 deg, report.html) and the JSON that command prints. Read only."""
    return _write_verified(reference_verified, tmp_path_factory.mktemp("reference") / "out")


@pytest.fixture(scope="session")
def write_verified():
    """``write_verified(verified, out, spec=None, report=True)``: a verified design written as ``strokeopt
    solve --out OUT --json`` writes it (:func:`_write_verified`); returns the directory and the JSON report."""
    return _write_verified


@pytest.fixture
def write_problem(tmp_path):
    """Write a variant of the reference problem: ``write_problem(lambda text: text.replace(...))``."""

    def _write(edit, name: str = "variant.toml") -> Path:
        path = tmp_path / name
        path.write_text(edit(REFERENCE.read_text(encoding="utf-8")), encoding="utf-8")
        return path

    return _write
