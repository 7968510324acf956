"""The HTML report as a person would see it: it parses, every figure is embedded and decodes, every
table cell is filled, limits are coloured by their verdict; where Chromium is installed, it renders
to a screenshot that is not blank."""
from __future__ import annotations

import base64
import html.parser
import io
import shutil
import subprocess

import numpy as np
import pytest

from cosim import cli

from helpers import SCENARIOS


class _Page(html.parser.HTMLParser):
    """The report's images, table cells (text and class) and whether every tag closed."""

    def __init__(self):
        super().__init__()
        self.images, self.cells, self.open, self._cell = [], [], [], None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "img":
            self.images.append(attrs.get("src", ""))
        elif tag in ("td", "th"):
            self._cell = [tag, attrs.get("class", ""), ""]
        if tag not in ("img", "meta", "br"):
            self.open.append(tag)

    def handle_endtag(self, tag):
        assert self.open and self.open[-1] == tag, f"</{tag}> closes <{self.open[-1] if self.open else None}>"
        self.open.pop()
        if tag in ("td", "th"):
            self.cells.append(tuple(self._cell))
            self._cell = None

    def handle_data(self, data):
        if self._cell is not None:
            self._cell[2] += data


def _read(path):
    page = _Page()
    page.feed(path.read_text())
    page.close()
    return page


def _assert_readable(page, figures_expected: int):
    assert not page.open, f"unclosed tags: {page.open}"
    assert len(page.images) == figures_expected
    for src in page.images:
        assert src.startswith("data:image/png;base64,")
        png = base64.b64decode(src.split(",", 1)[1], validate=True)
        from matplotlib.image import imread
        pixels = imread(io.BytesIO(png), format="png")
        assert pixels.shape[0] > 100 and pixels.shape[1] > 100 and np.ptp(pixels) > 0   # a drawing, not a blank
    empty = [c for c in page.cells if c[0] == "td" and not c[2].strip()]
    assert not empty, f"{len(empty)} empty table cells"


@pytest.fixture(scope="module")
def contact_run(tmp_path_factory):
    """A short curve entry on the contact (6 s, k = 0 and inf, valves off) checked with --report."""
    out = tmp_path_factory.mktemp("report") / "curve"
    code = cli.main(["check", str(SCENARIOS / "curve_entry_contact.yaml"), "--out", str(out), "--quiet", "--report",
                     "--k", "0,inf", "--set", "curve.duration_s=6", "--set", "curve.valve_settings=[false]",
                     "--set", "solver.jobs=1"])
    assert code == 0
    return out


@pytest.mark.slow
def test_check_writes_a_report_a_person_can_read(contact_run):
    report = contact_run / "report.html"
    assert report.exists() and (contact_run / "check.json").exists()
    page = _read(report)
    _assert_readable(page, len(list(contact_run.glob("*.png"))))
    text = report.read_text()
    for section in ("What ran", "EN 14363 assessment", "Checks", "Summary", "Verification", "Validity and warnings",
                    "Figures", "Provenance"):
        assert f"<h2>{section}</h2>" in text
    # the assessment: each zone's limits, every verdict coloured; this gentle run passes them all
    verdicts = [c for c in page.cells if c[1] in ("pass", "fail", "indicator")]
    assert verdicts and all(c[1] == "pass" for c in verdicts)
    assert "R&lt;250" in text and "yq_2m_p9985" in text and "Nadal" in text
    assert "http://" not in text and "https://" not in text and "<script" not in text   # self-contained


@pytest.mark.slow
def test_two_runs_side_by_side(contact_run, tmp_path):
    out = tmp_path / "two.html"
    assert cli.main(["report", str(contact_run), str(contact_run), "--out", str(out)]) == 0
    page = _read(out)
    _assert_readable(page, 2 * len(list(contact_run.glob("*.png"))))
    header = [c[2] for c in page.cells if c[0] == "th"]
    assert header.count("curve") >= 3        # a column per run in "what ran", the assessment, provenance


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("chromium") is None, reason="no Chromium here (apt-get install chromium)")
def test_the_report_renders_in_a_browser(contact_run, tmp_path):
    shot = tmp_path / "shot.png"
    subprocess.run(["chromium", "--headless", "--no-sandbox", "--disable-gpu", f"--screenshot={shot}",
                    "--window-size=1200,1600", (contact_run / "report.html").resolve().as_uri()],
                   check=True, capture_output=True, timeout=120)
    from matplotlib.image import imread
    pixels = imread(shot)[..., :3]
    # not blank: a page of text, tables and figures has many pixels far from the background
    assert (np.abs(pixels - pixels[0, 0]).sum(axis=-1) > 0.3).mean() > 0.02


def test_a_folder_that_is_not_a_run_is_refused(tmp_path):
    assert cli.main(["report", str(tmp_path)]) == 2


def test_legends_sit_beside_the_traces():
    from cosim.results.plots import Curve, Panel, draw_panels, pyplot
    t = np.linspace(0.0, 10.0, 200)
    curves = [Curve(t, np.sin(t + i), f"valves on, k = {k} W/K") for i, k in enumerate((0, 1, 10, 100, "inf"))]
    fig = draw_panels([Panel(curves, "time t [s]", "roll [mrad]"), Panel(curves[:2], "time t [s]", "air [g]")],
                      "title", ncols=2)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        box, legend = ax.get_window_extent(renderer), ax.get_legend().get_window_extent(renderer)
        assert legend.x0 >= box.x1 - 1e-6, "a legend overlaps its axes"
    # and no legend runs into the next panel or off the figure
    boxes = [ax.get_legend().get_window_extent(renderer) for ax in fig.axes]
    assert boxes[0].x1 <= fig.axes[1].get_window_extent(renderer).x0 and boxes[1].x1 <= fig.bbox.x1
    pyplot().close(fig)


@pytest.mark.slow
def test_compare_draws_the_wheel_rail_quantities_beside_the_first_run(contact_run):
    assert cli.main(["compare", str(contact_run)]) == 0
    png = contact_run.parent / f"compare_{contact_run.name}" / "compare_curve.png"
    assert png.exists() and png.stat().st_size > 10_000
