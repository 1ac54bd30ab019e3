#!/usr/bin/env bash
# Make docs/report-example.pdf and docs/report-example.png (its first page) from the reference design, and
# docs/report-knitting.png (its first four pages, two by two) from the knitting machine's fastest design
# (a stepper on a screw and lever, an elastic chain, no handover: the report follows the machine):
# `strokeopt solve --out` writes the design report, headless Chromium (Debian: apt-get install chromium)
# prints it to PDF, and its first page(s) become the PNG (pdftoppm, Debian: poppler-utils).
#   scripts/render_report.sh                      # python3 and chromium from PATH
#   PYTHON=/path/to/python CHROMIUM=/usr/bin/chromium scripts/render_report.sh
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
CHROMIUM=${CHROMIUM:-chromium}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

PYTHONPATH="$PWD/src${PYTHONPATH:+:$PYTHONPATH}" "$PYTHON" -m strokeopt solve problems/deco2000_needle_bar.toml \
    --out "$work/out" --plot none
flags=(--headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking
       --disable-component-update --disable-sync --user-data-dir="$work/profile")
url="file://$work/out/report.html"
"$CHROMIUM" "${flags[@]}" --no-pdf-header-footer --print-to-pdf="$PWD/docs/report-example.pdf" "$url" 2>"$work/pdf.log" \
    || { cat "$work/pdf.log" >&2; exit 1; }
# the first printed page (print CSS, as the PDF has it): poppler's pdftoppm (Debian: poppler-utils);
# without it, a screenshot of the first A4 screen (screen CSS)
if command -v pdftoppm >/dev/null; then
    pdftoppm -png -r 110 -f 1 -l 1 -singlefile docs/report-example.pdf docs/report-example
else
    "$CHROMIUM" "${flags[@]}" --window-size=794,1123 --force-device-scale-factor=1.5 --hide-scrollbars \
        --screenshot="$PWD/docs/report-example.png" "$url" 2>"$work/png.log" || { cat "$work/png.log" >&2; exit 1; }
fi
cp "$work/out/report.html" docs/report-example.html

# the knitting machine: its min_time design (the default objective breaks the stepper's pull-out curve)
PYTHONPATH="$PWD/src${PYTHONPATH:+:$PYTHONPATH}" "$PYTHON" -m strokeopt solve problems/knitting_stitch_density.toml \
    --objective min_time --out "$work/knit" --plot none
"$CHROMIUM" "${flags[@]}" --no-pdf-header-footer --print-to-pdf="$work/knit.pdf" "file://$work/knit/report.html" \
    2>"$work/knit.log" || { cat "$work/knit.log" >&2; exit 1; }
if command -v pdftoppm >/dev/null; then
    pdftoppm -png -r 70 -f 1 -l 4 "$work/knit.pdf" "$work/knit-page"
    "$PYTHON" - "$work" <<'PY'
import glob, sys
from PIL import Image  # matplotlib's own dependency
pages = [Image.open(p).convert("RGB") for p in sorted(glob.glob(sys.argv[1] + "/knit-page*.png"))]
w, h = pages[0].size
out = Image.new("RGB", (2 * w, h * ((len(pages) + 1) // 2)), "white")
for i, p in enumerate(pages):
    out.paste(p, ((i % 2) * w, (i // 2) * h))
out.save("docs/report-knitting.png", optimize=True)
PY
fi
ls -l docs/report-example.pdf docs/report-example.png docs/report-example.html docs/report-knitting.png
