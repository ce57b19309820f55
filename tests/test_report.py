"""`pdm-design report`: one self-contained HTML page, its animation data checked against the
simulator's run, and the page opened in a real headless Chromium: no console error, the
animation plays (its data-frame advances), the screenshot is not blank."""

import io
import json
import math
import re
import shutil
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.cli import main
from pdm_design.spec import load_spec
from pdm_design.verify import simulate_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
MANIP = PROBLEMS / "paper_manipulators.toml"
STAIRS = PROBLEMS / "paper_stairs_friction.toml"
CHROMIUM_FLAGS = ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                  "--disable-background-networking", "--disable-component-update",
                  "--disable-sync"]


@pytest.fixture(scope="module")
def pages(tmp_path_factory):
    out = {}
    for name, spec in (("manipulators", MANIP), ("stairs", STAIRS)):
        folder = tmp_path_factory.mktemp(name)
        result = CliRunner().invoke(main, ["report", str(spec), "--out", str(folder),
                                           "--no-tolerance"])
        assert result.exit_code == 0, result.output
        out[name] = folder / "report.html"
    return out


def test_the_page_is_self_contained(pages):
    for page in pages.values():
        text = page.read_text()
        assert "<link" not in text and "<script src" not in text and "@import" not in text
        assert re.findall(r'src="([^"]*)"', text)  # the drawing
        assert all(src.startswith("data:image/png;base64,")
                   for src in re.findall(r'src="([^"]*)"', text))
        assert 'id="pdm-animation"' in text and 'data-frame="0"' in text


def data_of(page):
    text = page.read_text()
    found = re.search(r'<script id="pdm-animation-data" type="application/json">(.*?)</script>',
                      text, re.S)
    return json.loads(found.group(1))


def test_the_animation_follows_the_run(pages):
    data = data_of(pages["manipulators"])
    assert data["x"][0] == -1250.0 and data["y"][0] == 3050.0  # the spec's start, mm
    spec = load_spec(MANIP)
    run = simulate_spec(spec, spec.design_at(), record_trajectory=True)
    assert abs(data["t"][-1] - run.trajectory["time"][-1]) < 1e-4
    # every palm rests at -alpha until it carries the object; its handover angle is a key
    for palm, stage in zip(data["palms"], run.stages):
        assert palm["keys"][0] == [0.0, -0.2]
        if stage.get("handover_time") is not None:
            assert [round(stage["handover_time"], 5), round(stage["handover_angle"], 6)] in \
                palm["keys"]
    # pivots: the pitch formulas, mm
    px, py = 2000 * (math.sin(0.2) + math.sin(0.6)), 2000 * (math.cos(0.2) - math.cos(0.6))
    for k, palm in enumerate(data["palms"]):
        assert abs(palm["pivot"][0] - k * px) < 1e-3 and abs(palm["pivot"][1] + k * py) < 1e-3


def test_the_ball_spins_by_the_integral_of_its_spin_rate(pages):
    data = data_of(pages["stairs"])
    spec = load_spec(STAIRS)
    run = simulate_spec(spec, spec.design_at(), record_trajectory=True)
    t, w = run.trajectory["time"], run.trajectory["omega"]
    # omega is constant in each flight: the spin angle grows by omega * duration per flight
    total = sum(w[i] * (t[i + 1] - t[i]) for i in range(len(t) - 1) if w[i] == w[i + 1])
    assert abs(data["spin"][-1] - total) < 1e-3 * max(1.0, abs(total))
    assert data["radius"] == 500.0


def test_yield_numbers_and_curves_go_on_the_page():
    from pdm_design.report.html import _yield

    text = _yield({"yield": 0.997, "rows": 100,
                   "survival": {"x": [1, 2, 3], "y": [1.0, 0.99, 0.97], "xlabel": "stage"}})
    assert "0.997" in text and text.count("data:image/png;base64,") == 1


# --------------------------------------------------------------------------- the browser

def _browser():
    """(playwright's sync API, the Chromium executable), or a skip saying why there is none."""
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        pytest.skip("no browser test: the playwright package is not installed "
                    "(pip install -e '.[test]')")
    path = next((p for p in ("/usr/bin/chromium", shutil.which("chromium"),
                             shutil.which("chromium-browser")) if p and Path(p).exists()), None)
    if path is None:
        pytest.skip("no browser test: no Chromium on this machine (.ci/run installs Debian's "
                    "chromium package when it can)")
    return sync_playwright, path


@pytest.fixture(scope="module")
def browser():
    sync_playwright, path = _browser()
    with sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=path, headless=True, args=CHROMIUM_FLAGS)
        yield chromium
        chromium.close()


def open_page(browser, page_path):
    page = browser.new_page(viewport={"width": 1200, "height": 900})
    problems, requests = [], []
    page.on("console", lambda m: problems.append(m.text) if m.type == "error" else None)
    page.on("pageerror", lambda e: problems.append(str(e)))
    page.on("request", lambda r: requests.append(r.url))
    page.goto(page_path.as_uri())
    return page, problems, requests


@pytest.mark.parametrize("kind", ["manipulators", "stairs"])
def test_the_report_plays_in_chromium(browser, pages, kind):
    page, problems, requests = open_page(browser, pages[kind])
    try:
        frames = int(page.get_attribute("#pdm-animation", "data-frames"))
        assert frames > 10
        first = int(page.get_attribute("#pdm-animation", "data-frame"))
        page.wait_for_timeout(800)
        later = int(page.get_attribute("#pdm-animation", "data-frame"))
        assert later > first or later < first - frames // 2  # advanced (or looped round)
        shot = page.screenshot()
        assert not problems, problems
        assert requests == [pages[kind].as_uri()]  # nothing fetched but the page itself
    finally:
        page.close()
    from PIL import Image

    image = Image.open(io.BytesIO(shot)).convert("RGB")
    colours = image.getcolors(maxcolors=1 << 16)
    assert colours is None or len(colours) > 50  # not blank: many colours
    assert image.getbbox() is not None


def test_pause_and_the_slider_control_the_frame(browser, pages):
    page, problems, _ = open_page(browser, pages["manipulators"])
    try:
        page.click("#pdm-play")
        held = page.get_attribute("#pdm-animation", "data-frame")
        page.wait_for_timeout(300)
        assert page.get_attribute("#pdm-animation", "data-frame") == held
        page.fill("#pdm-slider", "40")  # fill() sets the value and fires input
        assert page.get_attribute("#pdm-animation", "data-frame") == "40"
        page.click("#pdm-play")
        page.wait_for_timeout(300)
        assert int(page.get_attribute("#pdm-animation", "data-frame")) > 40
        assert not problems, problems
    finally:
        page.close()


def test_a_design_that_does_not_work_gets_its_page_and_exit_1(tmp_path):
    spec = tmp_path / "slip.toml"
    spec.write_text(MANIP.read_text().replace("friction = 0.8", "friction = 0.3"))
    result = CliRunner().invoke(main, ["report", str(spec), "--out", str(tmp_path / "out"),
                                       "--no-tolerance"])
    assert result.exit_code == 1 and "infeasible" in result.stderr
    page = (tmp_path / "out" / "report.html").read_text()
    assert "Do not build it" in page and 'id="pdm-animation"' in page
    assert len(data_of(tmp_path / "out" / "report.html")["t"]) > 10  # the run is animated


def test_a_missing_spec_is_bad_input_and_writes_nothing(tmp_path):
    result = CliRunner().invoke(main, ["report", str(tmp_path / "none.toml"), "--out",
                                       str(tmp_path / "out")])
    assert result.exit_code == 2 and "none.toml" in result.stderr
    assert not (tmp_path / "out").exists()


def test_a_saved_yield_analysis_goes_on_the_page(tmp_path):
    analysis = tmp_path / "yield.json"
    analysis.write_text(json.dumps({"yield": 0.9973, "survival": [[1, 1.0], [2, 0.998]]}))
    out = tmp_path / "out"
    result = CliRunner().invoke(main, ["report", str(MANIP), "--out", str(out),
                                       "--no-tolerance", "--yield", str(analysis)])
    assert result.exit_code == 0, result.output
    page = (out / "report.html").read_text()
    assert "<h2>Yield</h2>" in page and "0.9973" in page and 'alt="survival"' in page
    analysis.write_text("[1, 2]")
    result = CliRunner().invoke(main, ["report", str(MANIP), "--out", str(tmp_path / "b"),
                                       "--yield", str(analysis)])
    assert result.exit_code == 2 and "yield.json" in result.stderr
    assert not (tmp_path / "b").exists()


def _toleranced_spec(tmp_path, builds=300):
    """paper_manipulators with small statistical tolerances: every build works."""
    spec = tmp_path / "toleranced.toml"
    spec.write_text(MANIP.read_text().replace(
        "[verification]", f"[tolerances]\nbuilds = {builds}\npivot_x = {{ value = 0.02 }}\n"
        "pivot_y = { value = 0.02 }\nback_stop = { value = 0.005 }\n\n[verification]"))
    return spec


def test_the_report_computes_the_yield_of_the_specs_tolerances(tmp_path):
    spec = _toleranced_spec(tmp_path)
    result = CliRunner().invoke(main, ["report", str(spec), "--out", str(tmp_path / "out"),
                                       "--no-tolerance"])
    assert result.exit_code == 0, result.output
    page = (tmp_path / "out" / "report.html").read_text()
    # all 300 builds pass: the Wilson 95 % interval's low end is n / (n + z^2)
    z = 1.959963984540054
    assert f"100.00 % (95 % interval {100 * 300 / (300 + z * z):.2f} % to 100.00 %)" in page
    for plot in ("survival.png", "yield_scale.png", "sensitivity.png"):
        assert f'alt="{plot}"' in page
    assert "No build failed" in page
    result = CliRunner().invoke(main, ["report", str(spec), "--out", str(tmp_path / "no"),
                                       "--no-tolerance", "--no-yield"])
    assert result.exit_code == 0 and "<h2>Yield</h2>" not in (
        tmp_path / "no" / "report.html").read_text()


def test_the_yield_commands_document_goes_on_the_page_whole(tmp_path):
    spec = _toleranced_spec(tmp_path, builds=200)
    doc = json.loads(CliRunner().invoke(main, ["yield", str(spec), "--format", "json"]).stdout)
    doc["failures"] = {"tip": 7, "stall": 2}  # as the yield command lists them
    saved = tmp_path / "y.json"
    saved.write_text(json.dumps(doc))
    result = CliRunner().invoke(main, ["report", str(spec), "--out", str(tmp_path / "out"),
                                       "--no-tolerance", "--yield", str(saved)])
    assert result.exit_code == 0, result.output
    page = (tmp_path / "out" / "report.html").read_text()
    y = doc["yield"]
    assert (f"{100 * y['estimate']:.2f} % (95 % interval {100 * y['ci_low']:.2f} % to "
            f"{100 * y['ci_high']:.2f} %)") in page
    assert "<td>tip</td><td>7</td>" in page and "<td>stall</td><td>2</td>" in page
    for plot in ("survival.png", "yield_scale.png", "sensitivity.png"):
        assert f'alt="{plot}"' in page


def test_the_geometry_rows_carry_their_units_and_only_the_parts_built(tmp_path):
    from pdm_design.report.html import _values
    from pdm_design.report.units import built_parts, units_of

    table = _values(built_parts("manipulators", {
        "pitch_x": 0.5, "link_mass": 0.2, "link_inertia": 0.01, "pivot_friction_torque": 0.0,
        "pivot_damping": 0.0}), set(), units_of("manipulators"))
    assert "<td>kg</td>" in table and "<td>kg m^2</td>" in table and "N m s/rad" in table
    assert "500 mm" in table
    bare = built_parts("manipulators", {"pitch_x": 0.5, "link_mass": 0.0, "link_inertia": None,
                                        "link_count": 2, "pivot_friction_torque": 0.0,
                                        "pivot_damping": 0.0})
    assert bare == {"pitch_x": 0.5}
