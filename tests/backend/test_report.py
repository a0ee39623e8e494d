"""Stored assistant runs and the commissioning report over real HTTP.

The plant is made wrong as in test_assist.py: `sim.drive_gain` 22857 where the NC assumes
multi_gain 10000, so physics gives f = 22857 / 10000 and k = kv / f = 20 / 2.2857 1/s
[004 §3.6.2]. The report's plots are checked against the stored data through the range the
SVG frame declares (x tight to the data, y taking it in).
"""

from __future__ import annotations

import itertools
import json
import math
import re
import time
from collections.abc import Iterator
from html.parser import HTMLParser
from typing import Any

import pytest

from tests.backend.server import Server

F_PHYSICS = 22857 / 10000  # the drive's gain over the one the NC assumes


@pytest.fixture(scope="module")
def srv(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    s = Server(tmp_path_factory.mktemp("report") / "report.sqlite").start()
    yield s
    s.close()


def _wrong_drive_gain_run(srv: Server, mid: str) -> dict[str, Any]:
    body = {"changes": [{"scope": "axis", "target": "X", "name": "sim.drive_gain", "value": 22857}]}
    assert srv.http.patch(f"/api/machines/{mid}/parameters", json=body).status_code == 200
    r = srv.http.post(
        f"/api/machines/{mid}/assist/multi-gain",
        json={"axis": "X", "feed_mm_min": 200},
        timeout=120,
    )
    assert r.status_code == 200, r.text
    answer: dict[str, Any] = r.json()
    return answer


def _figures(result: dict[str, Any]) -> dict[str, float]:
    return {f["name"]: f["value"] for f in result["figures"]}


class _Doc(HTMLParser):
    """What the tests read from the report: figure rows, run articles, polylines, frames."""

    def __init__(self) -> None:
        super().__init__()
        self.figures: dict[str, list[str]] = {}  # name -> cell texts
        self.plots: list[dict[str, Any]] = []  # {"frame": attrs, "points": [...], "in": id}
        self._row: str | None = None
        self._cells: list[str] = []
        self._where = ""  # the run or trace article we are in
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "article":
            self._where = a.get("data-run") or a.get("data-trace") or ""
        if tag == "tr" and "data-figure" in a:
            self._row, self._cells = a["data-figure"], []
        if tag == "td" and self._row is not None:
            self._cells.append("")
        if tag == "rect" and a.get("class") == "frame":
            self.plots.append({"frame": a, "in": self._where, "points": []})
        if tag == "polyline":
            pts = [tuple(map(float, p.split(","))) for p in a["points"].split()]
            self.plots[-1]["points"].append(pts)

    def handle_endtag(self, tag: str) -> None:
        if tag == "tr" and self._row is not None:
            self.figures[self._row] = self._cells
            self._row = None

    def handle_data(self, data: str) -> None:
        self.text.append(data)
        if self._row is not None and self._cells:
            self._cells[-1] += data


def _read(html: str) -> _Doc:
    doc = _Doc()
    doc.feed(html)
    return doc


def _check_plot(plot: dict[str, Any], xs: list[float], ys: list[float]) -> None:
    """The polyline is the series mapped through the frame (x tight to the data, y taking it
    in): every point is a stored sample in place, time runs right, the first and last samples
    and the extremes are there (a long series is thinned to at most 2000 points)."""
    fr = plot["frame"]
    left, top = float(fr["x"]), float(fr["y"])
    width, height = float(fr["width"]), float(fr["height"])
    x0, x1, y0, y1 = (float(fr[k]) for k in ("data-x0", "data-x1", "data-y0", "data-y1"))
    assert (x0, x1) == (min(xs), max(xs))
    assert y0 <= min(ys) and y1 >= max(ys)

    def px(i: int) -> tuple[float, float]:
        x = left + (xs[i] - x0) / (x1 - x0) * width
        return x, top + (y1 - ys[i]) / (y1 - y0) * height  # SVG y grows downwards

    (pts,) = plot["points"]
    assert len(pts) == len(xs) if len(xs) <= 2000 else 1000 <= len(pts) <= 2000
    assert all(b[0] >= a[0] for a, b in itertools.pairwise(pts))  # time runs right
    assert pts[0] == pytest.approx(px(0), abs=0.006)
    assert pts[-1] == pytest.approx(px(len(xs) - 1), abs=0.006)
    step = width / (len(xs) - 1)  # px between samples
    for p in pts:
        i = round((p[0] - left) / step)  # the sample at this x
        assert p == pytest.approx(px(i), abs=0.006)
    assert min(p[1] for p in pts) == pytest.approx(px(ys.index(max(ys)))[1], abs=0.006)
    assert max(p[1] for p in pts) == pytest.approx(px(ys.index(min(ys)))[1], abs=0.006)


def test_a_multi_gain_run_is_stored_with_its_figures(srv: Server, lathe: str) -> None:
    answer = _wrong_drive_gain_run(srv, lathe)
    listed = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert len(listed) == 1
    info = listed[0]
    assert (info["assistant"], info["axis"], info["user"]) == ("multi-gain", "X", "tester")
    assert info["live"] is False and info["ok"] is True
    assert time.time() - 120 < info["time_unix"] <= time.time()
    stored = srv.http.get(f"/api/machines/{lathe}/assist/runs/{info['id']}").json()
    assert stored["result"] == answer  # the whole answer: figures, changes, series, notes
    assert _figures(stored["result"])["f"] == pytest.approx(F_PHYSICS, rel=0.01)
    assert "f = 2.28" in info["summary"] or "f = 2.29" in info["summary"]

    # newest first; another machine's runs are not its
    second = _wrong_drive_gain_run(srv, lathe)
    ids = [r["id"] for r in srv.http.get(f"/api/machines/{lathe}/assist/runs").json()]
    assert len(ids) == 2 and ids[0] > ids[1]
    assert _figures(second)["f"] == pytest.approx(F_PHYSICS, rel=0.01)  # nothing was applied
    assert srv.http.get(f"/api/machines/{lathe}/assist/runs/{ids[0] + 999}").status_code == 404
    assert srv.http.get("/api/machines/demo/assist/runs").json() == []


def test_runs_go_with_the_machine(srv: Server) -> None:
    mid = f"gone{time.monotonic_ns()}"
    assert srv.http.post("/api/machines", json={"id": mid, "demo": True}).status_code == 201
    srv.wait_powered(mid)
    r = srv.http.post(f"/api/machines/{mid}/assist/sign-check", json={"axis": "X"}, timeout=120)
    assert r.status_code == 200, r.text
    signed = srv.http.post(f"/api/machines/{mid}/report/sign-off", json={"name": "A. Engineer"})
    assert signed.status_code == 201
    assert len(srv.http.get(f"/api/machines/{mid}/assist/runs").json()) == 1
    assert srv.http.delete(f"/api/machines/{mid}").status_code == 204
    assert srv.http.post("/api/machines", json={"id": mid, "demo": True}).status_code == 201
    try:
        assert srv.http.get(f"/api/machines/{mid}/assist/runs").json() == []
        assert srv.http.get(f"/api/machines/{mid}/report/sign-offs").json() == []
    finally:
        srv.http.delete(f"/api/machines/{mid}")


def test_the_report_shows_the_run_its_figures_and_its_plot(srv: Server, lathe: str) -> None:
    answer = _wrong_drive_gain_run(srv, lathe)
    run = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()[0]
    r = srv.http.get(f"/api/machines/{lathe}/report")
    assert r.status_code == 200 and r.headers["content-type"].startswith("text/html")
    doc = _read(r.text)
    fig = _figures(answer)
    # the manual's figures with their units, as stored, and as physics says
    for name, unit in (("k", "1/s"), ("f", ""), ("kv", "1/s"), ("kv_new", "1/s")):
        cells = doc.figures[name]
        assert cells[0] == name and cells[2] == unit
        assert float(cells[1]) == pytest.approx(fig[name], rel=1e-5)
    assert fig["f"] == pytest.approx(F_PHYSICS, rel=0.01)
    assert float(doc.figures["k"][1]) == pytest.approx(20.0 / F_PHYSICS, rel=0.01)
    text = "".join(doc.text)
    assert "multi_gain by experiment [004 §3.6.2]" in text
    assert "getriebe[0].multi_gain_z" in text and "Run by tester" in text
    assert "No baseline set" in text  # no baseline service in this build
    assert lathe in text and "X (linear axis)" in text and "not signed off" in text
    (plot,) = [p for p in doc.plots if p["in"] == str(run["id"])]
    lag = next(s for s in answer["series"] if s["name"] == "lag")
    _check_plot(plot, lag["x"], lag["y"])
    assert "lag [mm]" in text and "time [s]" in text  # axis titles with units


def test_a_chosen_trace_is_plotted_from_its_stored_samples(srv: Server, lathe: str) -> None:
    # a trace of this machine (a description naming it, as an export has), samples known here
    t = [i * 0.001 for i in range(-200, 800)]
    y = [0.5 * math.sin(2 * math.pi * 3 * v) + 0.1 * v for v in t]
    meta = {
        "id": "x",
        "machine": lathe,
        "machine_name": lathe,
        "name": "X lag at 3 Hz",
        "notes": "",
        "source": "capture",
        "stored": True,
        "trigger": "level X.lag_mm rising 0",
        "forced": False,
        "created_unix": 0,
        "first_cycle": 1000,
        "trigger_cycle": 1200,
        "count": len(t),
        "cycle_s": 0.001,
        "channels": [{"name": "X.lag_mm", "unit": "mm", "kind": "float"}],
        "params_changed": 0,
        "params": [],
        "events": [],
    }
    rows = "".join(f"{1000 + i},{v!r}\n" for i, v in enumerate(y))
    csv = f"# meta: {json.dumps(meta)}\ncycle,X.lag_mm [mm]\n{rows}"
    r = srv.http.post(
        "/api/traces/import", content=csv.encode(), headers={"content-type": "text/csv"}
    )
    assert r.status_code == 201, r.text
    tid = r.json()["id"]
    report = srv.http.get(f"/api/machines/{lathe}/report", params={"trace": tid})
    assert report.status_code == 200, report.text
    doc = _read(report.text)
    (plot,) = [p for p in doc.plots if p["in"] == tid]
    _check_plot(plot, [(c - 1200) * 0.001 for c in range(1000, 1000 + len(t))], y)
    assert "X lag at 3 Hz" in "".join(doc.text)

    other = srv.http.get("/api/machines/demo/report", params={"trace": tid})
    assert other.status_code == 422 and lathe in other.json()["detail"]["message"]
    gone = srv.http.get(f"/api/machines/{lathe}/report", params={"trace": "nope"})
    assert gone.status_code == 404 and "nope" in gone.text
    many = srv.http.get(f"/api/machines/{lathe}/report", params=[("trace", tid)] * 9)
    assert many.status_code == 422 and "trace" in many.text


def test_sign_off_is_recorded_audited_and_shown(srv: Server, lathe: str) -> None:
    body = {"name": "Erika Mustermann", "role": "commissioning engineer", "remark": "X & Z <ok>"}
    r = srv.http.post(f"/api/machines/{lathe}/report/sign-off", json=body)
    assert r.status_code == 201, r.text
    signed = r.json()
    assert (signed["name"], signed["user"]) == ("Erika Mustermann", "tester")
    text = srv.http.get(f"/api/machines/{lathe}/report").text
    assert "Erika Mustermann" in text and "X &amp; Z &lt;ok&gt;" in text  # escaped
    assert "not signed off" not in text
    audit = srv.http.get(f"/api/machines/{lathe}/audit", params={"kind": "report"}).json()
    assert [row["action"] for row in audit["rows"]] == [
        "signed off by Erika Mustermann (commissioning engineer)"
    ]
    bad = srv.http.post(f"/api/machines/{lathe}/report/sign-off", json={"name": ""})
    assert bad.status_code == 422 and "name" in bad.text
    assert len(srv.http.get(f"/api/machines/{lathe}/report/sign-offs").json()) == 1


def test_the_pdf_is_a_real_pdf_of_the_report(srv: Server, lathe: str) -> None:
    r = srv.http.get(f"/api/machines/{lathe}/report.pdf", timeout=90)
    assert r.status_code == 200, r.text
    assert r.headers["content-type"] == "application/pdf"
    assert f"commissioning-report-{lathe}.pdf" in r.headers["content-disposition"]
    pdf = r.content
    assert pdf.startswith(b"%PDF-") and pdf.rstrip().endswith(b"%%EOF")
    pages = re.findall(rb"/Type\s*/Page(?![a-zA-Z])", pdf)
    assert len(pages) >= 5  # the cover and one page per section
    title = re.search(rb"/Title\s*\(([^)]*)\)", pdf)
    assert title is not None and lathe.encode() in title.group(1)


def test_without_chromium_the_pdf_is_a_clear_503(tmp_path: Any) -> None:
    s = Server(tmp_path / "db.sqlite", env={"INBETRIEB_CHROMIUM": str(tmp_path / "none")}).start()
    try:
        r = s.http.get("/api/machines/demo/report.pdf")
        assert r.status_code == 503 and "Chromium" in r.json()["detail"]["message"]
        assert s.http.get("/api/machines/demo/report").status_code == 200
    finally:
        s.close()


def test_the_report_lists_the_parameters_changed_since_the_baseline(
    srv: Server, lathe: str
) -> None:
    r = srv.http.post(
        f"/api/machines/{lathe}/versions", json={"name": "as delivered", "baseline": True}
    )
    assert r.status_code == 201, r.text
    doc = _read(srv.http.get(f"/api/machines/{lathe}/report").text)
    assert "No parameter of the NC differs from the baseline" in "".join(doc.text)
    body = {"changes": [{"scope": "axis", "target": "X", "name": "getriebe[0].kv", "value": 2500}]}
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json=body).status_code == 200
    text = srv.http.get(f"/api/machines/{lathe}/report").text
    row = re.search(r'<tr data-parameter="X.getriebe\[0\].kv">(.*?)</tr>', text)
    assert row is not None
    cells = re.findall(r"<td[^>]*>(.*?)</td>", row.group(1))
    # the demo's X kv 20/s (2000 in 0.01/s, P-AXIS-00099) as delivered, 25/s now
    assert cells[0] == "X" and "P-AXIS-00099" in cells[1]
    assert cells[2:6] == ["2000", "2500", "0.01/s", "20 → 25 1/s"]
    assert "No baseline set" not in text


def test_a_curve_run_up_is_stored_and_plots_points_and_fit_together(
    srv: Server, lathe: str
) -> None:
    """000 §2.8.4's polynomial on S1's gear 6, run up on a copy: the run is listed under the
    spindle, and its measured a(n) and the fitted curve share one plot (same units)."""
    poly: dict[str, float] = {"typ": 2, "n_grenz": 12000000, "a_konst": 16000, "a_min": 2000}
    poly |= {"b1": -0.88888888, "b2": 2.08333333e-5, "b3": -1.92901234e-10}
    changes = [
        {"scope": "axis", "target": "S1", "name": f"getriebe[5].beschl_kennlinie.{k}", "value": v}
        for k, v in poly.items()
    ]
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json={"changes": changes}).is_success
    r = srv.http.post(
        f"/api/machines/{lathe}/assist/curve-run-up",
        json={"axis": "S1", "gear": 6, "typ": 2},
        timeout=120,
    )
    assert r.status_code == 200, r.text
    (run,) = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    assert (run["assistant"], run["axis"]) == ("curve-run-up", "S1")
    doc = _read(srv.http.get(f"/api/machines/{lathe}/report").text)
    (plot,) = [p for p in doc.plots if p["in"] == str(run["id"])]
    assert len(plot["points"]) == len(r.json()["series"]) == 2
    assert "Acceleration curve from a run-up [000 §2.8.4]" in "".join(doc.text)


def test_a_frequency_response_is_plotted_on_a_logarithmic_frequency_axis(
    srv: Server, lathe: str
) -> None:
    """X on the drive cascade, its mechanics measured on a copy: the report's magnitude plot
    maps frequency logarithmically (the frame says so), each stored point in place."""
    values = {"sim.plant": "DRIVE_CASCADE", "drive.inertia_ratio": 3.0}
    values["sim.mech.anti_resonance"] = 60.0
    changes = [{"scope": "axis", "target": "X", "name": k, "value": v} for k, v in values.items()]
    assert srv.http.patch(f"/api/machines/{lathe}/parameters", json={"changes": changes}).is_success
    r = srv.http.post(
        f"/api/machines/{lathe}/assist/frequency-response", json={"axis": "X"}, timeout=120
    )
    assert r.status_code == 200, r.text
    mag = next(s for s in r.json()["series"] if s["name"] == "magnitude_db")
    (run,) = srv.http.get(f"/api/machines/{lathe}/assist/runs").json()
    doc = _read(srv.http.get(f"/api/machines/{lathe}/report").text)
    plots = [p for p in doc.plots if p["in"] == str(run["id"])]
    assert len(plots) == 3  # magnitude, phase, coherence: one unit each
    fr = plots[0]["frame"]
    assert fr["data-x-scale"] == "log"
    left, width = float(fr["x"]), float(fr["width"])
    x0, x1 = float(fr["data-x0"]), float(fr["data-x1"])
    assert (x0, x1) == (min(mag["x"]), max(mag["x"]))
    (pts,) = plots[0]["points"]
    span = math.log10(x1) - math.log10(x0)
    for p, f in zip(pts, mag["x"], strict=True):
        assert p[0] == pytest.approx(
            left + (math.log10(f) - math.log10(x0)) / span * width, abs=0.006
        )


def test_a_circle_is_drawn_as_a_polar_plot_at_its_stated_magnification(
    srv: Server, lathe: str
) -> None:
    """The circularity test on a copy (Z at kv 25/s against X's 20/s: an ellipse of about
    167 µm): the report draws each direction about the nominal circle, every stored point at
    the radius its deviation and the stated µm per division give."""
    change = {"scope": "axis", "target": "Z", "name": "getriebe[0].kv", "value": 2500}
    assert srv.http.patch(
        f"/api/machines/{lathe}/parameters", json={"changes": [change]}
    ).is_success
    r = srv.http.post(f"/api/machines/{lathe}/assist/circle", json={}, timeout=120)
    assert r.status_code == 200, r.text
    series = {s["name"]: s for s in r.json()["series"]}
    html = srv.http.get(f"/api/machines/{lathe}/report").text
    svg_tag = re.search(r'<svg[^>]*class="polar"[^>]*data-um-per-division="([\d.]+)"', html)
    assert svg_tag is not None
    per_div = float(svg_tag.group(1))
    assert 4 * per_div >= 167 / 2  # the ellipse's peak within the rings
    for name in ("CCW", "CW"):
        pts = re.search(rf'<polygon data-series="{name}"[^>]*points="([^"]*)"', html)
        assert pts is not None
        xy = [tuple(map(float, p.split(","))) for p in pts.group(1).split()]
        assert len(xy) == len(series[name]["x"])
        (px, py), deg, dr = xy[0], series[name]["x"][0], series[name]["y"][0]
        radius = 90 + dr / per_div * (160 - 14 - 90) / 4  # BASE + dr · px per µm
        assert math.hypot(px - 160, 160 - py) == pytest.approx(radius, abs=0.15)
        angle = math.degrees(math.atan2(160 - py, px - 160))
        assert abs((angle - deg + 180) % 360 - 180) < 0.5
