"""The HTML design report (`strokeopt report`, `solve --out DIR` -> DIR/report.html): every section, every
figure inlined, valid HTML, the numbers of `solve --json`; a real browser prints it when Chromium is installed."""

from __future__ import annotations

import json
import os
import re
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest

from strokeopt.cli.main import main
from strokeopt.report.design_report import SECTIONS

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = ROOT / "problems" / "deco2000_needle_bar.toml"
CHROMIUM = Path("/usr/bin/chromium")
VOID = {"meta", "br", "img", "input", "link", "hr", "col", "wbr", "source", "area", "base", "embed", "track"}


class Checker(HTMLParser):
    """A real HTML parser: tags balanced, every resource link, every data-key/data-value pair, section ids."""

    def __init__(self):
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.values: dict[str, str] = {}
        self.links: list[str] = []
        self.ids: list[str] = []
        self.figures = 0

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for name in ("src", "href", "xlink:href", "data", "poster"):
            if name in a:
                self.links.append(a[name])
        if "id" in a and tag == "section":
            self.ids.append(a["id"])
        if "data-key" in a:
            assert a["data-key"] not in self.values, f"data-key {a['data-key']} twice"
            self.values[a["data-key"]] = a["data-value"]
        if tag == "figure":
            self.figures += 1
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):  # <path ... />: opens and closes
        for name in ("src", "href", "xlink:href"):
            if name in dict(attrs):
                self.links.append(dict(attrs)[name])

    def handle_endtag(self, tag):
        if tag in VOID:
            return
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes <{self.stack[-1] if self.stack else 'nothing'}> at {self.getpos()}")
            return
        self.stack.pop()


def parse(path: Path) -> Checker:
    c = Checker()
    c.feed(path.read_text(encoding="utf-8"))
    c.close()
    return c


def _at(data, key: str):
    """The value at ``checks[3].value`` of a JSON report."""
    for part in re.findall(r"[^.\[\]]+|\[\d+\]", key):
        data = data[int(part[1:-1])] if part.startswith("[") else data[part]
    return data


def _value(text: str):
    return None if text == "null" else {"true": True, "false": False}.get(text, text)


@pytest.fixture(scope="module")
def solved(reference_written):
    """The reference design as `solve --json --out DIR` writes it (DIR/report.html among the files) and its
    JSON: the session's one verified solve (conftest.py)."""
    return reference_written.out, reference_written.summary


def test_every_section_every_figure_inlined_valid_html(solved):
    out, _ = solved
    path = out / "report.html"
    c = parse(path)
    assert not c.errors, c.errors[:5]
    assert c.stack == [], f"unclosed tags: {c.stack}"
    assert c.ids == [sid for sid, _ in SECTIONS]  # every section, in the order of the data flow
    # every figure embedded: the only links are the table of contents' anchors (no file, no URL, no script)
    assert c.links and all(link.startswith("#") for link in c.links), [x for x in c.links if not x.startswith("#")]
    text = path.read_text(encoding="utf-8")
    assert "src=" not in text and "<script" not in text.lower() and "<img" not in text
    assert c.figures >= 5 and text.count("<svg") == c.figures
    assert "@media print" in text and "break-before: page" in text
    assert "NaN" not in text and "nan</td>" not in text
    assert path.stat().st_size < 1_000_000


def test_numbers_equal_solve_json(solved):
    out, report = solved
    c = parse(out / "report.html")
    compared = 0
    for key, text in c.values.items():
        if key.startswith(("accuracy.", "verification.")):
            continue
        want, got = _at(report, key), _value(text)
        if isinstance(want, bool) or want is None:
            assert got is want, key
        elif isinstance(want, (int, float)):
            assert float(got) == want, key  # exactly: the report's value is the JSON's
        else:
            assert got == want, key
        compared += 1
    # the key numbers are among them: objective, torques, every check, every comparison row
    for key in ("objective_value", "peak_torque_N_m", "rms_torque_N_m", "checks[0].value", "comparison[1].peak_torque_N_m"):
        assert key in c.values
    assert compared >= len(report["checks"]) * 3 + len(report["comparison"]) * 5
    # the handover error the report shows is the solve's check (the same full servo simulation)
    check = next(x for x in report["checks"] if x["name"].startswith("handover accuracy"))
    assert float(c.values["accuracy.handover_error_mm"]) == check["value"]
    assert report["motor"] == "055U2B30" and report["pulley_teeth"] == 24  # the reference answer
    assert c.values["motor"] == "055U2B30"


def test_report_of_a_design_file_has_the_same_numbers(solved, capsys, tmp_path):
    out, report = solved
    html = tmp_path / "r.html"
    assert main(["report", str(REFERENCE), "--design", str(out / "design.json"), "--out", str(html), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["status"] == "ok" and info["scenes"] == ["release"] and info["size_bytes"] < 1_000_000
    c, d = parse(html), parse(out / "report.html")
    assert c.values == d.values  # read back from design.json: the numbers of the solve
    # the verification numbers are those `strokeopt verify` prints for the same design
    assert main(["verify", str(out / "design.json"), "--scene", "release", "--json"]) == 0
    ver = json.loads(capsys.readouterr().out)
    for key in ("impact_velocity_m_s", "release_angle_deg", "min_gap_N_mm"):
        assert float(c.values[f"verification.release.{key}"]) == ver[key]


def test_report_refuses_a_directory_or_a_non_html_name_before_solving(capsys, tmp_path):
    assert main(["report", str(REFERENCE), "--out", str(tmp_path)]) == 2
    assert "is a directory" in capsys.readouterr().err
    assert main(["report", str(REFERENCE), "--out", str(tmp_path / "r.pdf")]) == 2
    assert "name it .html" in capsys.readouterr().err
    assert main(["report", str(REFERENCE), "--out", str(tmp_path / "r.html"), "--scene", "nope"]) == 2
    assert "no scene 'nope'" in capsys.readouterr().err


@pytest.mark.slow  # two runs of a headless browser
def test_a_real_browser_prints_the_report(solved, tmp_path):
    if not CHROMIUM.exists():
        why = "no /usr/bin/chromium: the browser check needs Debian's chromium (apt-get install chromium)"
        if os.environ.get("CI") == "true":  # CI installs it (.ci/run): a missing browser there is a failure
            pytest.fail(why)
        pytest.skip(why)
    out, _ = solved
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
             "--disable-background-networking", "--disable-component-update", "--disable-sync",
             f"--user-data-dir={tmp_path / 'profile'}"]
    url = (out / "report.html").absolute().as_uri()
    pdf, png = tmp_path / "r.pdf", tmp_path / "r.png"
    run = subprocess.run([str(CHROMIUM), *flags, "--no-pdf-header-footer", f"--print-to-pdf={pdf}", url],
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr[-2000:]
    run = subprocess.run([str(CHROMIUM), *flags, "--window-size=1100,1500", f"--screenshot={png}", url],
                         capture_output=True, text=True, timeout=180)
    assert run.returncode == 0, run.stderr[-2000:]
    data = pdf.read_bytes()
    assert data.startswith(b"%PDF") and data.count(b"/Type /Page") - data.count(b"/Type /Pages") >= len(SECTIONS)
    assert png.read_bytes().startswith(b"\x89PNG") and png.stat().st_size > 50_000
