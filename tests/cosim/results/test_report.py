"""The HTML report as a person would see it: it parses, every figure is embedded and decodes, every
table cell is filled, limits are coloured by their verdict; the verdict at the top says PASS only
when every criterion and check holds, and agrees with the tables below it; each run keeps its own
limits side by side; where Chromium is installed, it renders to a screenshot that is not blank and
no table is wider than the page."""
from __future__ import annotations

import base64
import csv
import html
import html.parser
import io
import json
import math
import re
import shutil
import subprocess

import numpy as np
import pytest

from cosim import cli
from cosim.results.verdict import FAIL, NOT_ASSESSED, PASS, Judged, verdict

from helpers import SCENARIOS


class _Page(html.parser.HTMLParser):
    """The report's images, table cells (text and class), headings and whether every tag closed."""

    def __init__(self):
        super().__init__()
        self.images, self.cells, self.open, self._cell = [], [], [], None

    def handle_starttag(self, tag, attrs):
        attrs = dict(attrs)
        if tag == "img":
            self.images.append(attrs.get("src", ""))
        elif tag in ("td", "th"):
            self._cell = [tag, attrs.get("class", ""), ""]
        if tag not in ("img", "meta", "br", "wbr"):
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


def _text(path) -> str:
    """The report's visible text (tags and break opportunities dropped, entities decoded)."""
    return html.unescape(re.sub(r"<[^>]+>", "", path.read_text()))


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


# ----------------------------------------------------------------------------------- run folders
def _write_csv(path, rows):
    with path.open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)


def _limit_row(valves, k, quantity, zone, at, value, limit, kind="criterion", source="Nadal", unit="1"):
    status = "pass" if not math.isnan(value) and value <= limit else "fail"
    return {"valves": valves, "k_W_per_K": k, "quantity": quantity, "zone": zone, "at": at, "value": value,
            "limit": limit, "unit": unit, "kind": kind, "status": status, "source": source}


def _folder(tmp_path, name, radius=300.0, yq=(0.4, 0.5), info=None, check=None, summary=None):
    """A curve run's output folder as pneumorail writes it, without running anything: run.json,
    summary.csv, assessment_limits.csv (Y/Q per case, Y_qst of the radius, the ΔQ/Q0 indicator),
    check.json if given."""
    folder = tmp_path / name
    folder.mkdir()
    y_lim = 30e3 + 10.5e6 / radius
    info = {"kind": "curve_entry", "section": "curve", "name": name, "status": "complete", "diverged": None,
            "k_W_per_K": ["0", "inf"], "warnings": [], "metrics": {"yq_2m_p9985": max(yq)},
            "settings": {"circuit": {"layout": "four_point", "preset": "paper_table1", "valves": True}},
            "resolved": {"curve": {"speed_m_per_s": 10.0, "radius_m": radius, "direction": 1},
                         "track": {"model": "rigid"}}, **(info or {})}
    (folder / "run.json").write_text(json.dumps(info))
    rows = summary or [{"valves": "True", "k_W_per_K": k, "yq_2m_p9985": v, "validity": "ok"}
                       for k, v in zip(("0", "inf"), yq)]
    _write_csv(folder / "summary.csv", rows)
    limits = [_limit_row("True", k, "yq_2m_p9985", "R<250", "1R", v, 1.2) for k, v in zip(("0", "inf"), yq)]
    limits += [_limit_row("True", "0", "Y_2m_p50", "R<250", "1R", 20e3, y_lim, unit="N",
                          source=f"Y_qst: 30 kN + 10.5 MN m / R (R = {radius:g} m; assumed)"),
               _limit_row("True", "0", "dqq_2m_p9985", "R<250", "1L", 0.7, 0.6, kind="indicator",
                          source="twist-test unloading limit 0.6, as an indicator")]
    _write_csv(folder / "assessment_limits.csv", limits)
    if check is not None:
        (folder / "check.json").write_text(json.dumps(check))
    return folder


def _report(tmp_path, *folders):
    out = tmp_path / "report.html"
    assert cli.main(["report", *map(str, folders), "--out", str(out)]) == 0
    page = _read(out)
    _assert_readable(page, 0)
    return out, page


def _verdict_cells(page):
    """The verdict of each run (the first table)."""
    return [c for c in page.cells if "overall" in c[1].split()]


# ----------------------------------------------------------------------------------- the verdict
def _item(value, limit=1.0, status=None, counts=True, lower=False):
    holds = value >= limit if lower else value <= limit
    status = status or (NOT_ASSESSED if math.isnan(value) else PASS if holds else FAIL)
    return Judged("check", f"x <= {limit}", value, limit, status, counts, ">=" if lower else "<=")


def test_the_verdict_passes_only_when_every_counted_value_holds():
    assert verdict([]).status == "NOT ASSESSED" and verdict([]).worst is None
    assert verdict([_item(0.5, counts=False)]).status == "NOT ASSESSED"        # an indicator alone: nothing assessed
    passed = verdict([_item(0.5), _item(0.9), _item(2.0, limit=1.0, counts=False)])
    assert passed.status == "PASS" and passed.worst.value == 0.9               # the one closest to its limit
    assert verdict([_item(0.5), _item(math.nan)]).status == "NOT ASSESSED"     # a missing value: never PASS
    failed = verdict([_item(0.5), _item(math.nan), _item(1.1), _item(1.3)])
    assert failed.status == "FAIL" and failed.worst.value == 1.3 and failed.failed == 2
    lower = verdict([_item(30.0, limit=24.4, lower=True), _item(26.0, limit=24.4, lower=True)])
    assert lower.worst.value == 26.0 and lower.worst.margin == pytest.approx(1.6)


def test_the_report_opens_with_a_verdict_that_agrees_with_its_tables(tmp_path):
    passing = _folder(tmp_path, "passing")
    out, page = _report(tmp_path, passing)
    headings = re.findall(r"<h2>([^<]+)</h2>", out.read_text())
    assert headings[:4] == ["Verdict", "What ran", "Vehicle and circuit", "EN 14363 assessment"]
    text = _text(out)
    assert [c[2] for c in _verdict_cells(page)] == ["PASS"]
    # the worst criterion, its value, limit and margin, where: the largest Y/Q, on the outer rail
    assert "yq_2m_p9985" in text and "0.5" in text and "58 %" in text and "wheel 1R (outer rail)" in text
    # the indicator above its value is shown as such, not as a failure of the run
    assert "1 indicator(s) above their value" in text and "above (indicator)" in text
    # each limit's basis has its own column: stated by the standard, assumed, indicator
    assert "limit basis" in text and "stated by the standard" in text and "assumed" in text
    failing = _folder(tmp_path, "failing", yq=(0.4, 1.3))
    out, page = _report(tmp_path, failing)
    assert [c[2] for c in _verdict_cells(page)] == ["FAIL"]
    assert [c for c in page.cells if c[1] == "fail" and c[2] == "FAIL"]         # the assessment row that fails


def test_nothing_assessed_or_a_missing_value_is_not_a_pass(tmp_path):
    plain = _folder(tmp_path, "plain")
    (plain / "assessment_limits.csv").unlink()
    out, page = _report(tmp_path, plain)
    assert [c[2] for c in _verdict_cells(page)] == ["NOT ASSESSED"] and "nothing was assessed" in _text(out)
    stopped = _folder(tmp_path, "stopped", yq=(0.4, math.nan))
    out, page = _report(tmp_path, stopped)
    assert [c[2] for c in _verdict_cells(page)] == ["NOT ASSESSED"]
    diverged = _folder(tmp_path, "diverged", yq=(0.4, math.nan), info={"diverged": "k = inf: carbody rolled 0.3 rad"})
    out, page = _report(tmp_path, diverged)
    assert [c[2] for c in _verdict_cells(page)] == ["FAIL"] and "carbody rolled 0.3 rad" in _text(out)


def test_checks_name_the_basis_of_their_limits(tmp_path):
    check = {"status": "fail", "checks": [
        {"name": "yq_2m_p9985 <= 1.2", "metric": "yq_2m_p9985", "op": "<=", "limit": 1.2, "value": 0.5,
         "at": "k = inf, R<250, wheel 1R", "status": "pass"},
        {"name": "critical_speed_m_per_s >= 24.4", "metric": "critical_speed_m_per_s", "op": ">=", "limit": 24.4,
         "value": 20.0, "at": "k = 0", "status": "fail"},
        {"name": "dqq_2m_p9985 <= 0.6", "metric": "dqq_2m_p9985", "op": "<=", "limit": 0.6, "value": "nan",
         "at": "", "status": "error", "message": "no value: dqq_2m_p9985 is NaN in k = inf"},
        {"name": "validity: valves on, k = 0: pipe_mach", "status": "fail", "message": "outside the model's validity"}]}
    out, page = _report(tmp_path, _folder(tmp_path, "checked", check=check))
    text = _text(out)
    assert "the scenario's (checks:)" in text and "stated by the standard" in text       # = Nadal's limit
    assert "wheel 1R (outer rail)" in text and ">= 24.4 m/s" in text and "-4.4 m/s" in text
    assert [c[2] for c in _verdict_cells(page)] == ["FAIL"] and "pipe_mach" in text
    # a check whose value is missing (check.json: error) is not assessed, and says why
    assert ("unassessed", "not assessed") in [c[1:] for c in page.cells] and "dqq_2m_p9985 is NaN in k = inf" in text


def test_side_by_side_each_run_keeps_its_own_limits_and_facts(tmp_path):
    a, b = _folder(tmp_path, "r150", radius=150.0), _folder(tmp_path, "r300", radius=300.0)
    out, page = _report(tmp_path, a, b)
    text = _text(out)
    assert "R = 150 m; assumed" in text and "R = 300 m; assumed" in text
    assert "<= 100 kN" in text and "<= 65 kN" in text                    # Y_qst limit of each radius
    header = [c[2] for c in page.cells if c[0] == "th"]
    assert header.count("r150") >= 2 and header.count("r300") >= 2      # what ran, provenance: a column per run


def test_what_ran_says_what_failed_and_what_was_set(tmp_path):
    def vehicle(mass, how=None):
        return [{"group": "vehicle", "base": "preset metro_car_arb_dampers", "values": {"carbody_mass_kg": mass},
                 "set": {"carbody_mass_kg": how} if how else {}}]
    healthy = _folder(tmp_path, "healthy", info={"faults": [], "parameters": vehicle(17000.0)})
    burst = _folder(tmp_path, "burst", info={"faults": ["FR burst 5 cm² at 15 s"], "overrides": ["curve.duration_s=20"],
                                             "parameters": vehicle(21000.0, "--set")})
    old = _folder(tmp_path, "old")
    out, page = _report(tmp_path, healthy, burst, old)
    text = _text(out)
    assert "FR burst 5 cm² at 15 s" in text and "curve.duration_s=20" in text
    # the vehicle's data: the value --set put over the preset marked, the runs' difference framed
    cells = [c[1:] for c in page.cells]
    assert ("differs", "17000") in cells and ("set differs", "21000 (--set)") in cells
    # an older run.json: no parameter table, said so instead of failing
    assert "old: not recorded" in text


def test_the_summary_keeps_every_column_that_tells_the_cases_apart(tmp_path):
    rows = [{"valves": "False", "k_W_per_K": k, "airspring": model, "critical_speed_m_per_s": v,
             "nonlinear_critical_speed_m_per_s": nl, "critical_speed_by": by, "validity": "ok"}
            for k in ("0", "inf") for model, v, nl, by in (("circuit", 28.26, 28.26, "ramp-down"),
                                                           ("static", 40.2, "nan", "linear"))]
    info = {"kind": "stability", "section": "stability", "resolved": {"stability": {}},
            "summary_columns": ["valves", "k_W_per_K", "airspring", "critical_speed_m_per_s",
                                "nonlinear_critical_speed_m_per_s"],
            "warnings": ["the ramp-down at 0.25 m/s2 stopped at 30 m/s"]}
    folder = _folder(tmp_path, "stability", summary=rows, info=info)
    (folder / "assessment_limits.csv").unlink()
    out, page = _report(tmp_path, folder)
    header = [c[2] for c in page.cells if c[0] == "th"]
    for model in ("circuit", "static"):           # two rows per k, told apart by their airspring model
        assert any(f"airspring {model}" in h and "k = 0 W/K" in h for h in header)
    labels = [c[2] for c in page.cells if c[0] == "td"]
    assert {"nonlinear_critical_speed_m_per_s", "critical_speed_by"} <= set(labels)
    text = _text(out)
    assert "the ramp-down at 0.25 m/s2 stopped at 30 m/s" in text and "warnings: none" not in text


def test_the_parameters_say_where_each_value_came_from():
    from cosim.load import load_scenario
    from cosim.results.writer import parameter_groups
    scenario = load_scenario(SCENARIOS / "curve_burst.yaml", ["vehicle.carbody_mass_kg=21000"])
    groups = {g["group"]: g for g in parameter_groups(scenario)}
    vehicle = groups["vehicle"]
    assert vehicle["base"] == "preset metro_car_arb_dampers" and vehicle["values"]["carbody_mass_kg"] == 21000
    assert vehicle["set"] == {"carbody_mass_kg": "--set"}
    assert groups["circuit supply"]["set"] == {"p_Pa": "scenario"} and groups["circuit bellow"]["base"] == "preset paper_table1"


# ----------------------------------------------------------------------------------- a real run
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
    for section in ("Verdict", "What ran", "Vehicle and circuit", "EN 14363 assessment", "Checks", "Summary",
                    "Verification", "Validity and warnings", "Figures", "Provenance"):
        assert f"<h2>{section}</h2>" in text
    # the assessment: each zone's limits, every verdict coloured; this gentle run passes them all
    verdicts = [c for c in page.cells if c[1].split()[:1] in (["pass"], ["fail"], ["indicator"], ["unassessed"])]
    assert verdicts and all(c[1].split()[0] == "pass" for c in verdicts) and _verdict_cells(page)[0][2] == "PASS"
    shown = _text(report)
    assert "R<250" in shown and "yq_2m_p9985" in shown and "Nadal" in shown and "outer rail right" in shown
    assert "http://" not in text and "https://" not in text and "<script" not in text   # self-contained
    # the vehicle's data, from its preset, with what the command line set
    assert "preset paper_metro_car" in shown and "curve.duration_s=6" in shown


@pytest.mark.slow
def test_curve_runs_are_drawn_along_the_track_beside_time(contact_run):
    info = json.loads((contact_run / "run.json").read_text())
    for name in ("fig9_roll", "wheel_yq_valves=off", "wheel_dqq_valves=off", "wheelset_sum_y_valves=off"):
        assert (contact_run / f"{name}.png").exists() and (contact_run / f"{name}_along_track.png").exists()
        assert "outer rail right" in info["figures"][f"{name}_along_track.png"]
    shown = _text(contact_run / "report.html")
    assert "wheel_yq_valves=off.png] " in shown.replace("]", "] ") and "R = 100 m" in shown


@pytest.mark.slow
def test_two_runs_side_by_side(contact_run, tmp_path):
    out = tmp_path / "two.html"
    assert cli.main(["report", str(contact_run), str(contact_run), "--out", str(out)]) == 0
    page = _read(out)
    _assert_readable(page, 2 * len(list(contact_run.glob("*.png"))))
    header = [c[2] for c in page.cells if c[0] == "th"]
    assert header.count("curve") >= 2        # a column per run in "what ran" and the provenance


CHROMIUM = shutil.which("chromium")
#: written into a copy of the report (the report itself has no script): every table that reaches
#: beyond the page or scrolls inside itself, by its first header cell's text
MEASURE = ("<script>document.body.setAttribute('data-overflow', JSON.stringify(Array.from("
           "document.querySelectorAll('table')).filter(t => t.getBoundingClientRect().right > "
           "document.documentElement.clientWidth + 1 || t.scrollWidth > t.clientWidth + 1).map("
           "t => t.rows[0].textContent.slice(0, 80))) + ' page ' + document.documentElement.scrollWidth + ' of ' + "
           "document.documentElement.clientWidth);</script>")


def _overflowing(report, tmp_path, width_px: int):
    """The tables of ``report`` wider than a ``width_px`` window (headless Chromium), and the page's
    scroll width against its width."""
    page = tmp_path / f"measured_{width_px}.html"
    page.write_text(report.read_text().replace("</body>", MEASURE + "</body>"))
    dom = subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--dump-dom",
                          f"--window-size={width_px},1600", page.as_uri()],
                         check=True, capture_output=True, text=True, timeout=120).stdout
    found = html.unescape(re.search(r'data-overflow="([^"]*)"', dom).group(1))
    tables, _, widths = found.partition(" page ")
    scroll, _, client = widths.partition(" of ")
    return json.loads(tables), int(scroll), int(client)


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium here (apt-get install chromium)")
def test_the_report_renders_in_a_browser(contact_run, tmp_path):
    shot = tmp_path / "shot.png"
    subprocess.run([CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", f"--screenshot={shot}",
                    "--window-size=1200,1600", (contact_run / "report.html").resolve().as_uri()],
                   check=True, capture_output=True, timeout=120)
    from matplotlib.image import imread
    pixels = imread(shot)[..., :3]
    # not blank: a page of text, tables and figures has many pixels far from the background
    assert (np.abs(pixels - pixels[0, 0]).sum(axis=-1) > 0.3).mean() > 0.02


@pytest.mark.slow
@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium here (apt-get install chromium)")
def test_no_table_is_wider_than_the_page(contact_run, tmp_path):
    two = tmp_path / "two.html"
    assert cli.main(["report", str(contact_run), str(contact_run), "--out", str(two)]) == 0
    for report in (contact_run / "report.html", two):
        for width in (1400, 900):
            tables, scroll, client = _overflowing(report, tmp_path, width)
            assert tables == [], f"{report.name} at {width} px: tables wider than the page: {tables}"
            assert scroll <= client, f"{report.name} at {width} px: the page scrolls sideways ({scroll} > {client})"


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


def test_spans_mark_the_track_without_widening_it():
    from cosim.results.plots import Curve, Panel, Span, draw_panels, pyplot
    s = np.linspace(10.0, 160.0, 100)
    spans = [Span(0.0, 20.0, "straight", shade=False), Span(20.0, 50.0, "transition"), Span(50.0, 900.0, "arc")]
    fig = draw_panels([Panel([Curve(s, np.tanh(s / 50.0), "k = 0 W/K")], "s [m]", "Y/Q", hlines=[(1.2, "limit")],
                             spans=spans)])
    ax = fig.axes[0]
    lo, hi = ax.get_xlim()
    assert lo > 0.0 and hi < 200.0                         # the arc's end far beyond does not stretch the axis
    assert [t.get_text() for t in ax.texts if t.get_text() in ("straight", "transition", "arc")] == \
        ["straight", "transition", "arc"]
    assert ax.get_ylim()[1] > 1.2                          # the limit line stays below the labels' band
    pyplot().close(fig)


@pytest.mark.slow
def test_compare_draws_the_wheel_rail_quantities_beside_the_first_run(contact_run):
    assert cli.main(["compare", str(contact_run)]) == 0
    png = contact_run.parent / f"compare_{contact_run.name}" / "compare_curve.png"
    assert png.exists() and png.stat().st_size > 10_000


# ------------------------------------------------------------------ hostile folders (issue 39)
def _refused(capsys, *argv, names=()):
    """report exits 2 naming each of ``names``, with no traceback."""
    assert cli.main(["report", *map(str, argv)]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and all(str(n) in err for n in names), err
    return err


def test_a_figure_linked_from_outside_the_folder_is_not_embedded(tmp_path, capsys):
    # before: the linked file was base64-embedded into the report
    secret = tmp_path / "elsewhere.png"
    secret.write_bytes(b"\x89PNG secret")
    folder = _folder(tmp_path, "run")
    (folder / "figure.png").symlink_to(secret)
    err = _refused(capsys, folder, "--out", tmp_path / "r.html", names=(folder / "figure.png",))
    assert "symbolic link" in err and not (tmp_path / "r.html").exists()


def test_a_figure_linked_to_a_device_is_refused(tmp_path, capsys):
    # before: a link to /dev/zero crashed it (read to the memory limit)
    folder = _folder(tmp_path, "run")
    (folder / "zero.png").symlink_to("/dev/zero")
    _refused(capsys, folder, names=(folder / "zero.png",))


def test_a_figure_linked_inside_the_folder_is_embedded(tmp_path):
    folder = _folder(tmp_path, "run")
    (folder / "sub").mkdir()
    (folder / "sub" / "real.png").write_bytes(b"\x89PNG inside")
    (folder / "figure.png").symlink_to(folder / "sub" / "real.png")
    out = tmp_path / "r.html"
    assert cli.main(["report", str(folder), "--out", str(out)]) == 0
    assert _read(out).images == ["data:image/png;base64," + base64.b64encode(b"\x89PNG inside").decode()]


@pytest.mark.parametrize("marker, words", [("INCOMPLETE", "INCOMPLETE"), (".pneumorail.lock", "writing")])
def test_a_run_still_being_written_is_refused(tmp_path, capsys, marker, words):
    # before: exit 0, a report of half a run
    folder = _folder(tmp_path, "run")
    (folder / marker).write_text(str(__import__("os").getpid()))
    assert words in _refused(capsys, folder, names=(folder,))


def test_an_interrupted_run_is_reported_with_allow_incomplete_and_not_assessed(tmp_path):
    folder = _folder(tmp_path, "run", info={"status": "interrupted"})
    (folder / "INCOMPLETE").write_text("interrupted by SIGINT\n")
    assert cli.main(["report", str(folder), "--out", str(tmp_path / "r.html"), "--allow-incomplete"]) == 0
    assert "NOT ASSESSED" in _text(tmp_path / "r.html")


@pytest.mark.parametrize("file, content, words", [
    ("run.json", b"[1, 2]", "expected a JSON object"),
    ("run.json", b"{\"status\": ", "not valid JSON"),
    ("summary.csv", bytes(range(256)) * 4, "binary"),
    ("summary.csv", "valves,k_W_per_K\nTrue,0,extra\n".encode(), "line 2"),
    ("check.json", b"{\"checks\": {\"a\": 1}}", "checks"),
    ("check.json", b"{\"checks\": [{\"name\": \"x\", \"status\": \"maybe\"}]}", "checks[0].status"),
    ("check.json", b"{\"checks\": [[1]]}", "checks[0]"),
    ("assessment_limits.csv", b"quantity,value\nyq,1\n", "limit"),
    ("run.json", b"{\"settings\": [1], \"resolved\": 3}", "shape pneumorail writes"),
])
def test_reshaped_files_are_refused_naming_the_file(tmp_path, capsys, file, content, words):
    # before: a traceback (AttributeError, KeyError, UnicodeDecodeError ...)
    folder = _folder(tmp_path, "run")
    (folder / file).write_bytes(content)
    err = _refused(capsys, folder, names=(folder,))
    assert words in err and (file in err or words == "shape pneumorail writes")


def test_a_run_json_that_is_a_device_is_refused(tmp_path, capsys):
    folder = _folder(tmp_path, "run")
    (folder / "run.json").unlink()
    (folder / "run.json").symlink_to("/dev/zero")
    _refused(capsys, folder, names=(folder / "run.json",))


def test_a_sweep_folder_points_at_its_cases(tmp_path, capsys):
    # before: "not a pneumorail output folder", nothing more
    sweep = tmp_path / "sweep"
    (sweep / "cases").mkdir(parents=True)
    (sweep / "sweep.csv").write_text("case\nabc\n")
    case = _folder(sweep / "cases", "abc123")
    err = _refused(capsys, sweep, names=(sweep,))
    assert "cases" in err and str(case) in err


def test_a_lock_left_by_a_process_that_is_gone_does_not_block_the_report(tmp_path):
    gone = subprocess.Popen(["true"])
    gone.wait()
    folder = _folder(tmp_path, "run")
    (folder / ".pneumorail.lock").write_text(str(gone.pid))
    assert cli.main(["report", str(folder), "--out", str(tmp_path / "r.html")]) == 0
