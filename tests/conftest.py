"""Shared fixtures."""

from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
REFERENCE = ROOT / "problems" / "deco2000_needle_bar.toml"


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
