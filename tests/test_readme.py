"""The README runs as written: its set-up lines, every line of its command block, its Python example.

Each command runs as ``python -m strokeopt ...`` in a directory laid out like the repository (``problems/``
linked in), so what it writes lands in a temporary directory, and it must write only under ``out/`` (the
set-up line's figure: ``strokeopt-out/``), the folders `.gitignore` lists. A line ending in ``# exit N``
must exit N, any other 0. The lines that take long -- a trade-off, a sweep of rates, a design solve of a
full problem, and what reads its design.json -- carry the ``slow`` marker, as do the set-up line and the
Python example (each a verified reference solve); the fast lane (``pytest -m "not slow"``) runs the rest.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
TEXT = README.read_text(encoding="utf-8")
SETUP = ['pip install -e ".[dev]" && strokeopt solve problems/deco2000_needle_bar.toml',
         'pip install -e ".[dev]" && pytest']
TIMEOUT_S = 900


def fenced_blocks(text: str, lang: str) -> list[tuple[int, str]]:
    """Every fenced block of ``lang`` (``""``: a block without a language): (offset of the block, its text)."""
    return [(m.start(), m.group(2)) for m in re.finditer(r"^```(\w*)\n(.*?)^```", text, re.S | re.M)
            if m.group(1) == lang]


def command_block() -> list[str]:
    """The lines of the README's command block: the first bash block under '## Commands'."""
    start = TEXT.index("## Commands")
    block = next(block for at, block in fenced_blocks(TEXT, "bash") if at > start)
    return [line for line in block.splitlines() if line.strip()]


def expected_exit(line: str) -> int:
    """``# exit N`` at the end of a line: the code it documents; else 0."""
    m = re.search(r"#\s*exit\s+(\d+)\s*$", line)
    return int(m.group(1)) if m else 0


def argv(line: str) -> list[str]:
    """A README line as the argv of this interpreter: ``strokeopt ARGS`` -> ``python -m strokeopt ARGS``."""
    words = shlex.split(line, comments=True)
    assert words and words[0] == "strokeopt", f"not a strokeopt command: {line!r}"
    return [sys.executable, "-m", "strokeopt", *words[1:]]


def is_slow(line: str) -> bool:
    """Lines kept out of the fast lane: a trade-off, a sweep of rates, a design solve of a full problem (a known
    optimum's single move is quick), and what reads a design.json (its solve runs first)."""
    words = shlex.split(line, comments=True)
    spm = words[words.index("--spm") + 1] if "--spm" in words else ""
    solves = words[1] in ("solve", "report") and not any("known_optima/" in w for w in words)
    return words[1] == "tradeoff" or ":" in spm or solves or any(w.endswith("design.json") for w in words)


def run(line: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "MPLBACKEND": "Agg"}
    return subprocess.run(argv(line), cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S, env=env)


def layout(path: Path) -> Path:
    """A working directory laid out like the repository for the README's commands (inputs linked in)."""
    path.mkdir(parents=True, exist_ok=True)
    (path / "problems").symlink_to(ROOT / "problems", target_is_directory=True)
    return path


def check(line: str, done: subprocess.CompletedProcess, cwd: Path, allowed: set[str]) -> None:
    want = expected_exit(line)
    assert done.returncode == want, (f"{line}\nexit code {done.returncode}, the README says {want}\n"
                                     f"stderr: {done.stderr[-2000:]}")
    written = {p.name for p in cwd.iterdir()} - {"problems"}
    assert written <= allowed, f"{line} wrote {sorted(written - allowed)} into the working directory"


# --------------------------------------------------------------------------- the README's shape


def test_readme_is_at_most_150_lines():
    assert len(TEXT.splitlines()) <= 150


def test_readme_starts_with_the_two_setup_lines():
    first = fenced_blocks(TEXT, "bash")[0]
    assert TEXT.startswith("# strokeopt\n\n```bash\n"), "the README starts with its set-up block"
    assert first[1].splitlines() == SETUP
    assert SETUP[1] in (ROOT / ".ci" / "run").read_text(encoding="utf-8"), ".ci/run runs the README's test line"


def test_gitignore_lists_the_output_folders():
    ignored = (ROOT / ".gitignore").read_text(encoding="utf-8").splitlines()
    assert "out/" in ignored and "strokeopt-out/" in ignored


def test_the_command_block_writes_under_out():
    for line in command_block():
        words = shlex.split(line, comments=True)
        for flag in ("--out", "--plot"):
            if flag in words:
                assert words[words.index(flag) + 1].startswith("out/"), f"{line}: {flag} outside out/"


# --------------------------------------------------------------------------- the set-up line


@pytest.mark.slow  # the reference solve, verified
def test_setup_line_runs(tmp_path):
    line = SETUP[0].split("&&", 1)[1].strip()
    cwd = layout(tmp_path / "setup")
    check(line, run(line, cwd), cwd, {"strokeopt-out"})


# --------------------------------------------------------------------------- the command block


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """One working directory for the whole block (later lines read what earlier ones wrote) and the lines
    already run there."""
    return layout(tmp_path_factory.mktemp("readme") / "repo"), {}


def run_in(workdir, line: str) -> subprocess.CompletedProcess:
    """Run ``line`` once in the block's directory, first the lines that write the design files it reads."""
    cwd, done = workdir
    if line not in done:
        for folder in re.findall(r"(out/[\w.-]+)/design\.json", line):
            producer = next(p for p in command_block() if re.search(rf"--out {re.escape(folder)}(\s|$)", p))
            if not (cwd / folder / "design.json").exists():
                check(producer, run_in(workdir, producer), cwd, {"out"})
        done[line] = run(line, cwd)
    return done[line]


@pytest.mark.parametrize("line", [pytest.param(line, id=" ".join(line.split()[1:]),
                                               marks=[pytest.mark.slow] if is_slow(line) else [])
                                  for line in command_block()])
def test_command_block_line_runs(workdir, line):
    check(line, run_in(workdir, line), workdir[0], {"out"})


# --------------------------------------------------------------------------- the Python example

NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def python_example() -> tuple[str, str]:
    """The README's Python example and the output block shown after it."""
    start = TEXT.index("## From Python")
    code = next(block for at, block in fenced_blocks(TEXT, "python") if at > start)
    shown = next(block for at, block in fenced_blocks(TEXT, "") if at > start)
    return code, shown


def same_within_digits(shown: str, printed: str) -> bool:
    """Equal text, and each number within one unit of the last digit the README shows."""
    if NUMBER.sub("#", shown) != NUMBER.sub("#", printed):
        return False
    for a, b in zip(NUMBER.findall(shown), NUMBER.findall(printed)):
        digits = len(a.split("e")[0].split(".")[1]) if "." in a.split("e")[0] else 0
        scale = 10 ** int(a.split("e")[1]) if "e" in a else 1
        if abs(float(a) - float(b)) > 1.0001 * 10 ** -digits * scale:
            return False
    return True


@pytest.mark.slow  # the reference solve, verified
def test_python_example_prints_what_the_readme_shows(tmp_path):
    code, shown = python_example()
    cwd = layout(tmp_path / "python")
    done = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S,
                          env={**os.environ, "MPLBACKEND": "Agg"})
    assert done.returncode == 0, done.stderr[-2000:]
    printed = done.stdout.strip().splitlines()
    assert len(printed) == len(shown.strip().splitlines())
    for want, got in zip(shown.strip().splitlines(), printed):
        assert same_within_digits(want, got), f"README shows {want!r}, the example prints {got!r}"
    assert {p.name for p in cwd.iterdir()} == {"problems"}, "the example writes nothing"
