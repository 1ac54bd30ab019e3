"""The notebooks in notebooks/ are committed with their outputs (tables and figures), so a reader sees them
without running anything; `python scripts/run_notebooks.py` writes them. These tests keep those outputs
honest: each notebook was run top to bottom without an error and prints no path of one machine (fast), and
executing it again gives the numbers it shows, within tolerance, and the same figures per cell (slow).

Numbers are compared in the text a reader sees: stdout, and the text/plain and text/html of results. Two
numbers agree when they differ by at most RTOL relative (or ATOL absolute); see `numbers_agree`. A cell whose
output holds a value of this run only (a wall time the library prints) names it in its metadata,
``"varies": ["solved in \\S+ s"]`` (regular expressions), and that text is left out of the comparison; the
notebooks print no timings of their own.
"""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))

# 1e-3 relative: the notebooks and their prose quote three or four significant digits, so any change a reader
# could see is caught, while the differences between machines (round-off amplified by IPOPT's tolerance,
# 1e-8, and the integrator's, CVODES rtol 1e-5) stay a hundred times below it. 1e-6 absolute: the printed
# quantities are in engineering units (mm, N m, m/s, %); a value under 1e-6 is a solver residual (the margin
# of an active bound, a violation between nodes, a closure residual), which differs from machine to machine.
RTOL = 1e-3
ATOL = 1e-6
# a value at a rounding boundary may print one unit higher on another machine: forgiven when that unit is
# worth at most 1 % of the number (three significant digits or more); shorter numbers are compared as printed
LAST_DIGIT_SHARE = 0.01

NUMBER = re.compile(r"(?<![\w.])[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?(?!\w)(?!\.\d)")
# an absolute path: a slash that starts a name followed by another slash (/tmp/..., /home/...), or a drive
ABSOLUTE_PATH = re.compile(r"(?<![\w.~/])/[\w.+-]+/|\b[A-Za-z]:\\")


def _script():
    spec = importlib.util.spec_from_file_location("run_notebooks", ROOT / "scripts" / "run_notebooks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def code_cells(nb) -> list[tuple[int, dict]]:
    return [(i, c) for i, c in enumerate(nb.cells) if c.cell_type == "code"]


def output_text(cell) -> str:
    """What a reader reads of a cell's outputs: streams and the text/plain and text/html of results, with the
    run-specific text the cell's metadata names (``varies``) replaced by ``<varies>``."""
    parts = []
    for out in cell.get("outputs", []):
        if out.get("output_type") == "stream":
            parts.append(out.get("text", ""))
        elif out.get("output_type") in ("execute_result", "display_data"):
            parts += [out["data"][mime] for mime in ("text/plain", "text/html") if mime in out.get("data", {})]
    text = "\n".join(parts)
    for pattern in cell.get("metadata", {}).get("varies", []):
        text = re.sub(pattern, "<varies>", text)
    return text


def figure_count(cell) -> int:
    return sum(any(mime.startswith("image/") for mime in out.get("data", {})) for out in cell.get("outputs", []))


def _last_unit(token: str) -> float:
    """One unit in the last printed decimal place of a number printed with a decimal point, else 0."""
    mantissa, _, exponent = token.lower().partition("e")
    if "." not in mantissa:
        return 0.0
    return 10.0 ** (int(exponent or 0) - len(mantissa.split(".")[1]))


def numbers_agree(saved: str, fresh: str) -> bool:
    a, b = float(saved), float(fresh)
    if abs(a - b) <= max(RTOL * max(abs(a), abs(b)), ATOL):
        return True
    unit = max(_last_unit(saved), _last_unit(fresh))
    return abs(a - b) <= unit * (1 + 1e-9) and unit <= LAST_DIGIT_SHARE * max(abs(a), abs(b))


def _line_of(text: str, start: int) -> str:
    line = text[text.rfind("\n", 0, start) + 1:].split("\n", 1)[0].strip()
    return line if len(line) <= 120 else line[:117] + "..."


def compare_cell(saved_cell, fresh_cell) -> str | None:
    """The first difference between a cell's saved and fresh outputs, or None."""
    saved_text, fresh_text = output_text(saved_cell), output_text(fresh_cell)
    saved_numbers, fresh_numbers = list(NUMBER.finditer(saved_text)), list(NUMBER.finditer(fresh_text))
    for k, (s, f) in enumerate(zip(saved_numbers, fresh_numbers)):
        if not numbers_agree(s.group(), f.group()):
            return (f"number {k + 1} of {len(saved_numbers)}: saved {s.group()}, fresh {f.group()} "
                    f"(saved line: {_line_of(saved_text, s.start())!r}; fresh line: "
                    f"{_line_of(fresh_text, f.start())!r})")
    if len(saved_numbers) != len(fresh_numbers):
        return f"{len(saved_numbers)} numbers saved, {len(fresh_numbers)} fresh"
    if figure_count(saved_cell) != figure_count(fresh_cell):
        return f"{figure_count(saved_cell)} figures saved, {figure_count(fresh_cell)} fresh"
    saved_words, fresh_words = NUMBER.sub("#", saved_text).split(), NUMBER.sub("#", fresh_text).split()
    if saved_words != fresh_words:
        k = next((k for k, (s, f) in enumerate(zip(saved_words, fresh_words)) if s != f),
                 min(len(saved_words), len(fresh_words)))
        return (f"text differs at word {k + 1}: saved {' '.join(saved_words[k:k + 6])!r}, "
                f"fresh {' '.join(fresh_words[k:k + 6])!r}")
    return None


def compare_notebooks(name: str, saved, fresh) -> str | None:
    """The first cell whose fresh outputs differ from the saved ones, named by notebook and cell, or None."""
    saved_cells, fresh_cells = code_cells(saved), code_cells(fresh)
    if len(saved_cells) != len(fresh_cells):
        return f"{name}: {len(saved_cells)} code cells saved, {len(fresh_cells)} fresh"
    for (index, s), (_, f) in zip(saved_cells, fresh_cells):
        difference = compare_cell(s, f)
        if difference:
            return (f"{name} cell {index} (In [{s.get('execution_count')}]): {difference}; if the change is meant, "
                    f"regenerate with python scripts/run_notebooks.py {name[:2]}")
    return None


def test_there_are_notebooks():
    assert len(NOTEBOOKS) >= 1


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_is_committed_run(path):
    """Every code cell ran, in order from the top, and shows its outputs: no error, no path of one machine."""
    nb = nbformat.read(path, as_version=4)
    cells = code_cells(nb)
    counts = [c.get("execution_count") for _, c in cells]
    assert counts == list(range(1, len(cells) + 1)), (
        f"{path.name}: execution counts {counts}; run it top to bottom with python scripts/run_notebooks.py")
    empty = [i for i, c in cells if not c.get("outputs")]
    assert not empty, f"{path.name}: cells {empty} have no outputs"
    errors = [i for i, c in cells for out in c["outputs"] if out.get("output_type") == "error"]
    assert not errors, f"{path.name}: cells {errors} show an error"
    for i, c in cells:
        text = output_text(c)
        found = ABSOLUTE_PATH.search(text)
        assert not found, f"{path.name} cell {i} prints an absolute path: {_line_of(text, found.start())!r}"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.name for p in NOTEBOOKS])
def test_notebook_runs_and_shows_its_outputs(path):
    """Executed again as scripts/run_notebooks.py executes it, the notebook gives the numbers it shows."""
    saved = nbformat.read(path, as_version=4)
    fresh = _script().execute(path)  # raises CellExecutionError, naming the cell, on any failing cell
    errors = [i for i, c in code_cells(fresh) for out in c.get("outputs", []) if out.get("output_type") == "error"]
    assert not errors
    difference = compare_notebooks(path.name, saved, fresh)
    assert difference is None, difference


def _cell(text: str, figures: int = 0, **metadata):
    outputs = [nbformat.v4.new_output("stream", name="stdout", text=text)]
    outputs += [nbformat.v4.new_output("display_data", data={"image/png": "", "text/plain": "<Figure>"})] * figures
    return nbformat.v4.new_code_cell("", outputs=outputs, execution_count=1, metadata=metadata)


def _notebook(*cells):
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_markdown_cell("# title"), *cells]
    return nb


def test_comparison_finds_a_planted_difference():
    saved = _notebook(_cell("peak 1.295 N m at 600 spm, margin 2.955e-08\nyield 100.0 %", figures=1))
    assert compare_notebooks("x.ipynb", saved, saved) is None
    fresh = _notebook(_cell("peak 1.311 N m at 600 spm, margin 2.955e-08\nyield 100.0 %", figures=1))
    message = compare_notebooks("x.ipynb", saved, fresh)
    assert message.startswith("x.ipynb cell 1 (In [1]): number 1 of 4: saved 1.295, fresh 1.311")


@pytest.mark.parametrize("saved, fresh, agrees", [
    ("peak 1.295 N m", "peak 1.2962 N m", True),    # within 1e-3 relative
    ("peak 1.295 N m", "peak 1.298 N m", False),    # 2.3e-3
    ("impact 2.85 m/s", "impact 2.86 m/s", True),   # one unit in the last place of three digits (a rounding)
    ("impact 2.85 m/s", "impact 2.87 m/s", False),  # two units
    ("margin 2.955e-08", "margin 3.1e-08", True),   # a solver residual: under the absolute floor
    ("peak 1.295 N m", "peak 1.295 N m 7", False),  # one number more
    ("peak 1.295 N m", "peak 1.295 N cm", False),   # a word changed
])
def test_comparison_tolerance(saved, fresh, agrees):
    message = compare_cell(_cell(saved), _cell(fresh))
    assert (message is None) is agrees, message


def test_comparison_of_short_numbers_and_figures():
    assert compare_cell(_cell("error 0.070 mm"), _cell("error 0.071 mm"))  # a unit worth 1.4 %: compared as printed
    assert compare_cell(_cell("gain 0.5"), _cell("gain 0.6"))  # a %g number with its zeros stripped
    assert compare_cell(_cell("16/16 samples"), _cell("15/16 samples"))
    assert compare_cell(_cell("a", figures=2), _cell("a", figures=1)) == "2 figures saved, 1 fresh"


def test_a_cell_names_what_varies():
    saved = _cell("optimal, solved in 0.48 s, mesh 40", varies=[r"solved in \S+ s"])
    fresh = _cell("optimal, solved in 1.93 s, mesh 40", varies=[r"solved in \S+ s"])
    assert compare_cell(saved, fresh) is None
    assert compare_cell(_cell("optimal, solved in 0.48 s, mesh 40"), _cell("optimal, solved in 1.93 s, mesh 40"))


def test_absolute_paths_are_found():
    for text in ("report /tmp/tmpab12/report.html", "'/home/ann/x.toml'", "C:\\Users\\x", "(/root/work/a.toml)"):
        assert ABSOLUTE_PATH.search(text), text
    for text in ("../problems/a.toml", "m/s^2", "1/(2 T_sigma)", "rockit / strokeopt", "N m/s2"):
        assert not ABSOLUTE_PATH.search(text), text
