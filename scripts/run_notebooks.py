"""Execute the notebooks in notebooks/ in place and write them back with their outputs.

Each notebook runs in a fresh kernel with notebooks/ as its working directory, as a user opens it,
from its first cell to its last; a failing cell stops the run and leaves that notebook unchanged.
Figures are drawn at 72 dpi (each notebook's first cell) and their PNGs stored with a palette of 256
colours: 10-50 KB a figure, every notebook under 160 KB.
The committed outputs are what a reader sees on the repository's pages, and tests/test_notebooks.py
executes every notebook again and compares its numbers with the committed ones.

    python scripts/run_notebooks.py                 # every notebook (a minute or two)
    python scripts/run_notebooks.py 03 06           # the notebooks whose names start with 03 or 06
"""

from __future__ import annotations

import base64
import io
import sys
import time
from pathlib import Path

import nbformat
from nbclient import NotebookClient

NOTEBOOKS = Path(__file__).resolve().parents[1] / "notebooks"
TIMEOUT_S = 1200  # per cell; the slowest cells (a sweep, a tolerance study) take minutes on a loaded machine


def execute(path: Path) -> nbformat.NotebookNode:
    """The notebook at ``path`` executed top to bottom in notebooks/ (raises on the first failing cell)."""
    nb = nbformat.read(path, as_version=4)
    client = NotebookClient(nb, timeout=TIMEOUT_S, kernel_name="python3", record_timing=False,
                            coalesce_streams=True,  # one stdout output per cell, however the kernel flushed it
                            resources={"metadata": {"path": str(path.parent)}})
    client.execute()
    return nb


def small_png(data: str) -> str:
    """A base64 PNG of a figure, on white, re-encoded with a palette of 256 colours (a third of its size)."""
    from PIL import Image  # a dependency of matplotlib

    image = Image.open(io.BytesIO(base64.b64decode(data))).convert("RGBA")
    flat = Image.alpha_composite(Image.new("RGBA", image.size, "white"), image).convert("RGB")
    out = io.BytesIO()
    flat.quantize(colors=256, method=Image.Quantize.MEDIANCUT).save(out, "PNG", optimize=True)
    return base64.b64encode(out.getvalue()).decode() if out.tell() < len(data) * 3 // 4 else data


def shrink_figures(nb: nbformat.NotebookNode) -> None:
    """Every PNG output of ``nb`` stored with a palette (:func:`small_png`), in place."""
    for cell in nb.cells:
        for output in cell.get("outputs", []):
            if "image/png" in output.get("data", {}):
                output["data"]["image/png"] = small_png(output["data"]["image/png"])


def main(prefixes: list[str]) -> int:
    paths = sorted(NOTEBOOKS.glob("*.ipynb"))
    if prefixes:
        paths = [p for p in paths if any(p.name.startswith(x) for x in prefixes)]
    if not paths:
        print(f"no notebook in notebooks/ starts with {' or '.join(prefixes)}", file=sys.stderr)
        return 2
    for path in paths:
        start = time.perf_counter()
        nb = execute(path)
        shrink_figures(nb)
        nbformat.write(nb, path)
        print(f"{path.relative_to(NOTEBOOKS.parent)}: {time.perf_counter() - start:.0f} s, "
              f"{path.stat().st_size / 1024:.0f} KB", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
