"""Shared fixtures."""

from __future__ import annotations

from pathlib import Path

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


@pytest.fixture
def write_problem(tmp_path):
    """Write a variant of the reference problem: ``write_problem(lambda text: text.replace(...))``."""

    def _write(edit, name: str = "variant.toml") -> Path:
        path = tmp_path / name
        path.write_text(edit(REFERENCE.read_text(encoding="utf-8")), encoding="utf-8")
        return path

    return _write
