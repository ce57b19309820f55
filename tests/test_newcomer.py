"""What a newcomer tripped on: a start below palm 1, bounds that bind silently, which condition
limits the tolerance, and the messages of the command line.

Expected numbers come from closed forms written out here (palm 1's top at first_pivot_y + l cos
alpha, dimensional analysis) or from a second solve (a relaxed requirement or bound).
"""

import json
import math
import tomllib
from pathlib import Path

import pytest
from click.testing import CliRunner
from test_fuzz_cli import dumps

from pdm_design.api import design
from pdm_design.cli import main
from pdm_design.solve import optimize
from pdm_design.spec import parse_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"
ROBUST = PROBLEMS / "manipulators_robust.toml"


def run(*args):
    result = CliRunner().invoke(main, [str(a) for a in args])
    return result.exit_code, result.stdout, result.stderr


def robust_data(**design):
    data = tomllib.loads(ROBUST.read_text())
    data["design"].update(design)
    return data


def write(tmp_path, data, name="spec.toml"):
    path = tmp_path / name
    path.write_text(dumps(data))
    return path


# ------------------------------------------------------------------ 1. a start below palm 1

def test_a_start_below_palm_1_for_every_design_is_bad_input_naming_the_palm_height(tmp_path):
    # first pivot 5 m up: palm 1's top is at 5 + 2 cos(alpha) >= 5 + 2 cos(0.6) over alpha's
    # bounds [0, 0.6], above the start at y = 3.05 m whatever is chosen
    spec = write(tmp_path, robust_data(first_pivot_y=5.0))
    code, out, err = run("optimize", spec)
    lowest = 5.0 + 2.0 * math.cos(0.6)
    assert code == 2 and out == ""
    assert err.startswith(f"error: {spec}: initial.position[1]: expected a start above palm 1's "
                          "top surface")
    assert f"{lowest:.6g} m" in err and "alpha = 0.6" in err
    assert f"found 3.05 m, {lowest - 3.05:.4g} m below it" in err
    assert "solver_error" not in err and "Traceback" not in err


@pytest.mark.parametrize("command", ["optimize", "simulate", "sheet", "check"])
def test_a_link_of_a_million_metres_under_the_papers_start_is_refused_in_words(tmp_path,
                                                                                command):
    # docs/spec.md allows link_length = 1e6; with the paper's start (y = 3.05 m) palm 1 stands
    # 1e6 cos(0.2) m above it: the run was a solver_error (the fall speed a square root of a
    # negative number at every start), now a refusal naming the start and the palm
    data = tomllib.loads((PROBLEMS / "paper_manipulators.toml").read_text())
    data["design"]["link_length"] = 1e6
    spec = write(tmp_path, data)
    args = [command, spec] + (["--out", tmp_path / "sheet"] if command == "sheet" else [])
    code, out, err = run(*args)
    assert code == 2
    text = out + err
    assert "initial.position[1]" in text and f"{1e6 * math.cos(0.2):.6g} m for this design" in text


def test_some_designs_fit_the_start_but_none_works_is_infeasible_naming_start_and_palm(tmp_path):
    # first pivot 1.3 m up: palm 1's top, 1.3 + 2 cos(alpha), is below the start (3.05 m) for
    # alpha > acos(0.875) = 0.505 only, where no design works. Every start of the multistart
    # was below palm 1 and IPOPT stopped at once: solver_error, 0 iterations.
    spec = write(tmp_path, robust_data(first_pivot_y=1.3))
    code, out, err = run("optimize", spec, "--format", "json", "--no-verify")
    doc = json.loads(out)
    assert code == 1 and doc["status"] == "infeasible"
    top = 1.3 + 2.0 * math.cos(doc["design"]["alpha"])
    message = doc["status_message"]
    assert message.startswith(f"The object starts at y = 3.05 m, below palm 1's top surface at "
                              f"y = {top:.6g} m")
    assert f"as low as y = {1.3 + 2.0 * math.cos(0.6):.6g} m" in message
    assert doc["violations"][0] == f"the object starts {top - 3.05:.4g} m below the first " \
                                   "palm's top surface"
    assert doc["solver"]["iterations"] > 0


def test_the_report_leads_with_the_start_and_labels_the_least_violation_design(tmp_path):
    spec = write(tmp_path, robust_data(first_pivot_y=1.3))
    code, out, _ = run("optimize", spec, "--no-verify")
    lines = out.splitlines()
    assert code == 1 and lines[1].startswith("status: infeasible - The object starts at y = "
                                             "3.05 m, below palm 1's top surface")
    assert any(x.startswith("  alpha ") and x.endswith("(least violation)") for x in lines)
    assert "(optimised)" not in out
    why = lines[lines.index("why it does not work:") + 1]
    assert why.startswith("  - the object starts ") and "below the first palm" in why


def test_a_start_above_only_part_of_the_bounds_is_found_there(tmp_path):
    # link 3.2 m, alpha in [0, 0.6] guessed at 0.1: palm 1's top (3.2 cos alpha) is above the
    # start at 3.05 m for alpha < acos(3.05 / 3.2) = 0.309, the guess included; the optimum
    # lies where the palm is below the start
    data = robust_data(link_length=3.2, alpha={"min": 0.0, "max": 0.6, "initial": 0.1})
    result = optimize(parse_spec(data), check_samples=0, linearise=False)
    assert result.status.value == "optimal"
    assert 3.2 * math.cos(result.design["alpha"]) < 3.05


def _robust_at(scale: float):
    """problems/manipulators_robust.toml at lengths x scale, speeds x sqrt(scale) (the same
    device in units of its link), the first pivot moved down to keep heights within 1e6 m."""
    data = tomllib.loads(ROBUST.read_text())
    for table, keys in ((data["scene"]["body"], ("width", "height")),
                        (data["scene"]["palm"], ("width", "thickness"))):
        for key in keys:
            table[key] *= scale
    x0, y0 = (v * scale for v in data["initial"]["position"])
    shift = 1e6 if y0 > 1e6 else 0.0
    data["initial"]["position"] = [x0, y0 - shift]
    data["initial"]["velocity"] = [v * math.sqrt(scale) for v in data["initial"]["velocity"]]
    data["design"]["link_length"] *= scale
    data["design"]["first_pivot_y"] = -shift
    return parse_spec(data)


@pytest.fixture(scope="module")
def robust_result():
    return optimize(_robust_at(1.0), check_samples=0, linearise=False)


@pytest.mark.parametrize("scale", [2e-5, 5e5])  # links of 40 microns and of 1e6 m
def test_the_documented_extremes_of_size_solve_to_the_same_design(robust_result, scale):
    # docs/spec.md: lengths from 1e-6 m (the palm thickness, 0.05 x scale) to 1e6 m (the link)
    result = optimize(_robust_at(scale), check_samples=0, linearise=False)
    assert result.status.value == "optimal", result.stats.return_statuses
    assert result.tolerance["dx"] / scale == pytest.approx(robust_result.tolerance["dx"],
                                                           rel=1e-5)
    assert result.design["alpha"] == pytest.approx(robust_result.design["alpha"], abs=1e-5)


# ------------------------------------------------------------------ 3. variables at a bound

def test_at_bound_is_within_a_millionth_of_the_range():
    from pdm_design.spec.model import at_bound

    assert at_bound(3.0 - 0.9e-6 * 2.5, 0.5, 3.0) == "max"
    assert at_bound(3.0 - 1.1e-6 * 2.5, 0.5, 3.0) is None
    assert at_bound(0.5 + 0.9e-6 * 2.5, 0.5, 3.0) == "min"
    assert at_bound(1.0, 1.0, 1.0) is None  # pinned: not free, at no bound


@pytest.fixture(scope="module")
def stairs_doc():
    code, out, _ = run("optimize", PROBLEMS / "stairs_design.toml", "--format", "json",
                       "--no-verify")
    assert code == 0
    return json.loads(out)


def test_a_launch_speed_held_by_its_bound_is_flagged(stairs_doc):
    # A second solve with the bound raised from 3 to 3.5 m/s finds a larger tolerance: the
    # bound binds, and the document says so.
    assert stairs_doc["design"]["launch_speed"] == 3.0
    assert stairs_doc["at_bounds"] == {"launch_speed": "max"}
    data = tomllib.loads((PROBLEMS / "stairs_design.toml").read_text())
    data["design"]["launch_speed"]["max"] = 3.5
    wider = optimize(parse_spec(data), check_samples=0, linearise=False)
    assert wider.tolerance["rise"] > 1.01 * stairs_doc["tolerance"]["rise"]


def test_the_report_has_a_line_for_variables_at_a_bound():
    code, out, _ = run("optimize", PROBLEMS / "stairs_design.toml", "--no-verify")
    assert code == 0 and "  at a bound: launch_speed (max 3 m/s)\n" in out
    code, out, _ = run("optimize", ROBUST, "--no-verify")  # alpha and beta inside their bounds
    assert code == 0 and "at a bound" not in out


# ------------------------------------------------------------------ 4. what limits the tolerance

def test_the_stairs_tolerance_names_the_nose_and_the_launch_speed_bound(stairs_doc):
    limited = stairs_doc["tolerance"]["limited_by"]
    assert [e["condition"] for e in limited] == ["nose_clearance", "nose_clearance", "bound"]
    assert all("flight 20" in e["where"] for e in limited[:2])
    assert sum(e["share"] for e in limited[:2]) == pytest.approx(1.0, abs=1e-3)
    assert limited[2] == {"condition": "bound", "where": "launch_speed at its max 3",
                          "share": None}


def _tolerance(spec, **requirements):
    result = optimize(spec, requirements={**spec.requirements, **requirements},
                      check_samples=0, linearise=False)
    assert result.status.value == "optimal"
    return result.tolerance["dx" if spec.kind == "manipulators" else "rise"]


@pytest.mark.parametrize("name", ["manipulators_robust.toml", "stairs_design.toml"])
def test_the_condition_named_first_limits_the_tolerance_and_a_slack_one_does_not(name):
    # A second solve: asking 0.01 more margin of the condition named first shrinks the
    # tolerance; asking it of a condition not named (slack at the optimum) changes nothing.
    from pdm_design.spec import load_spec

    spec = load_spec(PROBLEMS / name)
    outcome = design(spec, verify=False)
    limited = outcome.tolerance["limited_by"]
    first = limited[0]["condition"]
    named = {e["condition"] for e in limited}
    slack = min((m for m, v in outcome.analysis.margins.items()
                 if m not in named and v > 0.1 + spec.requirements.get(m, 0.0)),
                key=lambda m: outcome.analysis.margins[m])
    base = _tolerance(spec)
    need = spec.requirements.get(first, 0.0) + 0.01
    assert _tolerance(spec, **{first: need}) < (1 - 1e-3) * base
    need = spec.requirements.get(slack, 0.0) + 0.01
    assert _tolerance(spec, **{slack: need}) == pytest.approx(base, rel=1e-6)


def test_the_report_says_what_limits_the_tolerance():
    code, out, _ = run("optimize", ROBUST, "--no-verify")
    line = next(x for x in out.splitlines() if x.startswith("  limited by: "))
    assert line.startswith("  limited by: lift_off (at the handover, fastest carry) ")


# ------------------------------------------------------------------ 2. pdm-design init

def test_init_manipulators_lands_on_palm_1s_centre_and_optimizes_as_written(tmp_path):
    spec = tmp_path / "row.toml"
    code, out, _ = run("init", "manipulators", "--out", spec)
    assert code == 0 and str(spec) in out
    data = tomllib.loads(spec.read_text())
    (x0, y0), (vx, vy) = data["initial"]["position"], data["initial"]["velocity"]
    g, l, a = data["scene"]["gravity"], data["design"]["link_length"], data["design"]["alpha"]
    # palm 1 (pivot at the origin) rests at -alpha: its top surface centred at
    # (-l sin a, l cos a); the horizontal launch falls y0 - l cos a onto it
    assert vy == 0.0
    t = math.sqrt(2.0 * (y0 - l * math.cos(a)) / g)
    assert x0 + vx * t == pytest.approx(-l * math.sin(a), abs=1e-8)
    code, out, _ = run("optimize", spec, "--format", "json")
    doc = json.loads(out)
    assert code == 0 and doc["status"] == "optimal" and doc["verification"]["passed"]
    landing = doc["approach"]["landing_point"]
    assert landing[0] == pytest.approx(-l * math.sin(a), abs=1e-8)
    assert landing[1] == pytest.approx(l * math.cos(a), abs=1e-12)


def test_init_stairs_lands_mid_tread_and_optimizes_as_written(tmp_path):
    spec = tmp_path / "stairs.toml"
    assert run("init", "stairs", "--out", spec)[0] == 0
    data = tomllib.loads(spec.read_text())
    code, out, _ = run("optimize", spec, "--format", "json")
    doc = json.loads(out)
    assert code == 0 and doc["status"] == "optimal" and doc["verification"]["passed"]
    # the periodic bounce falls h0 from its apex e^2 h0 to the next tread (rise (1 - e^2) h0):
    # it lasts (1 + e) sqrt(2 h0 / g), and the tread is the distance flown in it
    g, h0 = data["scene"]["gravity"], data["initial"]["drop_height"]
    e, v0 = data["design"]["restitution"], doc["design"]["launch_speed"]
    tread = v0 * (1.0 + e) * math.sqrt(2.0 * h0 / g)
    code, out, _ = run("simulate", spec, "--format", "json", "--stages", 3)
    assert code == 0
    for stage in json.loads(out)["stages"]:
        assert stage["landing_x"] == pytest.approx(tread / 2, rel=1e-9)


def test_init_to_stdout_and_not_over_a_file(tmp_path):
    code, out, _ = run("init", "stairs")
    assert code == 0 and tomllib.loads(out)["scene"]["kind"] == "stairs"
    spec = tmp_path / "mine.toml"
    spec.write_text("# my edits\n")
    code, out, err = run("init", "manipulators", "--out", spec)
    assert code == 2 and err.startswith("error: command line: --out: expected the name of a "
                                        "file that does not exist yet")
    assert spec.read_text() == "# my edits\n"


# ------------------------------------------------------------------ 6. the linearised coordinates

def test_the_linearised_coordinates_name_the_pivots_the_sheet_lists(tmp_path):
    # a row of 10: the sheet lists pivots 1 to 10; pivot 11 is not part of it, only the height
    # of what receives the object from manipulator 10 (its handover angle) is
    from pdm_design.sheet import sheet_for

    data = tomllib.loads(ROBUST.read_text())
    data["verification"]["stages"] = 10
    spec = write(tmp_path, data)
    code, out, _ = run("optimize", spec, "--format", "json", "--no-verify", "--linearised")
    names = json.loads(out)["tolerance"]["linearised"]["coordinates"]
    listed = [item["manipulator"] for item in sheet_for(spec).items]
    assert listed == list(range(1, 11))
    assert names == [f"dx{k}" for k in listed] + [f"dy{k}" for k in listed] + ["dy_receiver"]


# ------------------------------------------------------------------ 7. simulate --plot

def test_simulate_says_where_it_wrote_the_figures(tmp_path):
    plot = tmp_path / "run.png"
    code, out, _ = run("simulate", PROBLEMS / "paper_stairs_frictionless.toml", "--plot", plot)
    assert code == 0 and plot.is_file() and out.endswith(f"figures written to {plot}\n")
    code, out, err = run("simulate", PROBLEMS / "paper_stairs_frictionless.toml", "--plot",
                         plot, "--format", "json")
    assert code == 0 and json.loads(out) and f"figures written to {plot}" in err


# ------------------------------------------------------------------ 8. a tip in words

def _first_failure(**kw):
    """The tip onset: the first `rock` event (the object turns about its edge from there)."""
    from test_sim_manipulators import make

    from pdm_design.scenes.manipulators.sim import simulate_manipulators

    scene, design = make(**kw)
    return next(e for e in simulate_manipulators(scene, design, stages=2).events
                if e.kind == "rock")


def test_a_tip_in_the_carry_reaches_the_supported_edge_without_contradiction():
    # the carry tips where the force point (h/2) tan th behind the centre reaches the rear
    # edge of a w-wide base: -w/2, printed the same on both sides
    failure = _first_failure(width=0.4, height=0.7)
    assert failure.detail.startswith("the contact force reaches the rear edge of the supported "
                                     "base (-0.2 m from the base's centre; support [-0.2, +0.2] m)")
    assert "outside" not in failure.detail


def test_a_tip_at_the_landing_says_by_how_much_the_impulse_misses_the_support():
    from test_sim_manipulators import ALPHA, first_landing, momentum_speed

    failure = _first_failure(width=0.2, height=2.0)
    _, _, vx, vy = first_landing()
    u = momentum_speed(vx, vy)
    px, py = u * math.cos(ALPHA) - vx, u * math.sin(ALPHA) - vy
    point = -(2.0 / 2) * px / py  # where the impulse line meets the base, + ahead
    assert point > 0.1
    assert failure.detail.startswith(f"the impulse passes the front edge of the supported base "
                                     f"by {point - 0.1:.3g} m ({point:+.6g} m from")


# ------------------------------------------------------------------ 9. command-line errors

@pytest.mark.parametrize("command", ["optimize", "simulate", "sheet"])
def test_a_directory_given_as_a_spec_is_an_error_in_the_tools_words(tmp_path, command):
    code, out, err = run(command, tmp_path)
    assert code == 2 and out == ""
    assert err == f"error: {tmp_path}: expected a spec file, found a directory\n"


@pytest.mark.parametrize("args, words", [
    (["optimize", ROBUST, "--accuracy", "rtol=0"],
     "--accuracy: rtol: expected a number >= 2.22e-14 (100 machine epsilons) and < 1, found 0"),
    (["simulate", ROBUST, "--stages", "0"],
     "--stages: expected an integer from 1 to 10000000, found '0'"),
    (["simulate", ROBUST, "--offset", "3:x"], "--offset: expected K:DX,DY"),
    (["optimize", ROBUST, "--format", "xml"], "--format: 'xml' is not one of 'text', 'json'"),
    (["optimize", ROBUST, "--bogus"], "No such option '--bogus' (see `"),
])
def test_option_errors_all_come_in_the_tools_format(args, words):
    code, out, err = run(*args)
    assert code == 2 and out == ""
    assert err.startswith(f"error: command line: {words}") and "Usage:" not in err


# ------------------------------------------------------------------ one toleranced quantity

def _each_additive(weights):
    """Output sum_q w_q * (sum of q's deviations): quantity q's variance share is
    w_q^2 Var(q) / sum of them (parts of one quantity are independent)."""
    import numpy as np

    from pdm_design.tolerances.outcome import BuildOutcome

    def run(deviations, stages):
        y = sum(w * deviations[q].sum(axis=1) for q, w in weights.items())
        n = len(y)
        return BuildOutcome(np.zeros(n, dtype=int), np.full(n, "", dtype=object), y,
                            np.ones(n, dtype=bool))

    return run


@pytest.mark.parametrize("count", [1, 2, 3])
def test_any_number_of_per_part_quantities_gets_its_variance_share(count):
    from pdm_design.tolerances.sensitivity import sobol_indices

    names = ("rise", "tread", "pivot_y")[:count]
    weights = dict(zip(names, (3.0, 2.0, 1.0)))
    tolerances = [(q, "each", 0.3, "normal") for q in names]
    rows = sobol_indices(_each_additive(weights), tolerances, stages=4, samples=2048, seed=1)
    total = sum(w * w for w in weights.values())  # equal tolerances: shares are w^2 / sum w^2
    assert [r["quantity"] for r in rows] == list(names)
    for r in rows:
        share = weights[r["quantity"]] ** 2 / total
        assert abs(r["index"] - share) <= max(r["confidence"], 1e-12)
    if count == 1:  # one quantity explains all the variance: both indices are 1 exactly
        assert (rows[0]["index"], rows[0]["first"], rows[0]["confidence"]) == (1.0, 1.0, 0.0)


def _one_tolerance_spec(tmp_path, problem, tolerances, stages=3):
    data = tomllib.loads((PROBLEMS / problem).read_text())
    data["tolerances"] = {"builds": 64, "seed": 0, "confirm": 2, **tolerances}
    data["verification"]["stages"] = stages
    data.pop("expect", None)
    return write(tmp_path, data)


ONE_TOLERANCE = [("manipulators_long_row_yield.toml", "pivot_y", 0.1),
                 ("stairs_yield.toml", "rise", 0.005)]


@pytest.mark.parametrize("problem, quantity, value", ONE_TOLERANCE)
def test_yield_with_one_per_part_tolerance_gives_it_index_1(tmp_path, problem, quantity,
                                                                value):
    spec = _one_tolerance_spec(tmp_path, problem,
                               {quantity: {"value": value, "applies_to": "each"}})
    code, out, err = run("yield", spec, "--format", "json")
    assert code == 0, err
    rows = json.loads(out)["sensitivity"]
    assert [(r["quantity"], r["index"]) for r in rows] == [(quantity, 1.0)]


@pytest.mark.parametrize("problem, quantity, value", ONE_TOLERANCE)
def test_report_with_one_per_part_tolerance_writes_its_page(tmp_path, problem, quantity, value):
    spec = _one_tolerance_spec(tmp_path, problem,
                               {quantity: {"value": value, "applies_to": "each"}})
    code, out, err = run("report", spec, "--out", tmp_path / "page", "--no-tolerance")
    assert code == 0, err
    assert "<h2>Yield</h2>" in (tmp_path / "page" / "report.html").read_text()


# ------------------------------------------------------------------ tolerances sized for a yield

def _unfilled_boxes(figure):
    from matplotlib.patches import Rectangle

    return [p for p in figure.axes[0].patches
            if isinstance(p, Rectangle) and not p.get_fill() and p.get_edgecolor()[0] > 0.5]


def _sized_sheet(tmp_path, kind):
    from test_yield_target_stairs import sized_text

    if kind == "stairs":  # the stairs_design optimum fixed, rise and tread to size, 10 bounces
        text = sized_text()
    else:  # the row with its design free, 5 stages
        text = (PROBLEMS / "manipulators_yield_target.toml").read_text()
        text = text.replace("stages = 20", "stages = 5").replace("min_yield = 0.9973", "")
    path = tmp_path / f"{kind}.toml"
    path.write_text(text)
    from pdm_design.sheet import sheet_for

    return sheet_for(path, tolerance=False)


@pytest.mark.parametrize("kind, axes, columns", [
    ("manipulators", ("pivot_x", "pivot_y"), ("pivot_x_tolerance_m", "pivot_y_tolerance_m")),
    ("stairs", ("rise", "tread"), ("rise_tolerance_m", "tread_tolerance_m"))])
def test_a_sheet_sized_for_a_yield_shows_the_placement_tolerance_everywhere(tmp_path, kind, axes,
                                                                           columns):
    import dataclasses

    from pdm_design.plugin import of
    from pdm_design.sheet import sheet_csv
    from pdm_design.sheet.drawing import draw
    from pdm_design.sheet.parts import tolerance_entries
    from pdm_design.solve.yield_allocation import linearised_yield_function

    sheet = _sized_sheet(tmp_path, kind)
    spec, stages = sheet.spec, sheet.spec.verification.stages
    t = sheet.items[0][columns[0]]
    # the value is the linearised yield's size (the linearised yield at it, and at 1e-3 more,
    # brackets the target), times the Monte Carlo check's common factor (solve/yield_check.py)
    from pdm_design.solve.yield_allocation import allocate_for_yield
    from pdm_design.solve.yield_check import check_allocation

    allocation = allocate_for_yield(spec.scene, spec.design_at(), spec.tolerances, stages=stages)
    checked = check_allocation(spec.scene, spec.design_at(), allocation.tolerances, set(axes),
                               target=allocation.target, stages=stages,
                               accuracy=spec.verification.accuracy)
    linear = t / checked.factor
    sized = dataclasses.replace(spec.tolerances, items=tuple(
        dataclasses.replace(q, value=linear) if q.quantity in axes else q
        for q in spec.tolerances))
    bigger = dataclasses.replace(sized, items=tuple(
        dataclasses.replace(q, value=1.001 * linear) if q.quantity in axes else q
        for q in sized))
    at = linearised_yield_function(spec.scene)
    assert at(spec.scene, spec.design_at(), sized, stages)["yield"] >= 0.9973 - 1e-9
    assert at(spec.scene, spec.design_at(), bigger, stages)["yield"] < 0.9973
    assert all(item[c] == t for item in sheet.items for c in columns)  # every row, both axes
    assert sorted(row[3] for row in sheet.summary if row[3] is not None) == [t, t]
    assert f"{t:.12g}"[:8] in sheet_csv(sheet).splitlines()[1]
    table = "\n".join(of(sheet.spec).table_rows(sheet))  # the PDF's coordinate pages
    assert table.count(f"+-{t * 1e3:.3g}") == 2 * stages
    entries = {e.quantity: e.value for e in tolerance_entries(sheet)}
    assert [entries[q.replace("_", " ")] for q in axes] == [t, t]  # once each, no box beside
    assert not any("(box)" in q for q in entries)
    if kind == "manipulators":  # the legend's red boxes, one per pivot, 2 t wide
        boxes = _unfilled_boxes(draw(sheet))
        assert len(boxes) == stages
        assert all(b.get_width() == pytest.approx(2e3 * t) for b in boxes)


# ------------------------------------------------------------------ restitution 1

def _stairs_at_restitution_1(tmp_path, objective):
    data = tomllib.loads((PROBLEMS / "stairs_design.toml").read_text())
    data["design"]["restitution"] = 1.0
    data.pop("expect")
    data["objective"] = objective
    return write(tmp_path, data)


@pytest.mark.parametrize("objective", [{}, {"max_min_margin": 1.0}])
def test_restitution_1_with_a_free_variable_solves_to_the_flat_floor(tmp_path, objective):
    code, out, err = run("optimize", _stairs_at_restitution_1(tmp_path, objective),
                         "--format", "json")
    doc = json.loads(out)
    assert code == 0 and doc["status"] == "optimal", (doc["status"], doc["violations"])
    # periodic orbit at eps = 1: rise (1 - eps^2) h0 = 0, tread vx (1 + eps) V / g with the
    # vertical speed V = sqrt(2 g h0) of the drop (docs: the paper's periodic orbit)
    v0, g = doc["design"]["launch_speed"], 9.81
    assert doc["design"]["rise"] == 0.0
    assert doc["design"]["tread"] == pytest.approx(2.0 * v0 * math.sqrt(2.0 * g * 1.0) / g,
                                                   rel=1e-9)
    assert doc["verification"]["passed"]


def test_restitution_1_under_a_tolerance_box_says_the_floor_is_flat(tmp_path):
    code, out, err = run("optimize", _stairs_at_restitution_1(
        tmp_path, {"max_offset_tolerance": 1.0}), "--format", "json", "--no-verify")
    doc = json.loads(out)
    assert code == 1 and doc["status"] == "infeasible"
    assert any(v.startswith("restitution 1 gives a periodic rise (1 - restitution^2) h0 = 0")
               and "no tolerance box exists" in v for v in doc["violations"])


# ------------------------------------------------------------------ beta not beyond alpha

@pytest.mark.parametrize("alpha, beta, keys", [
    (0.5, 0.4, ("design.alpha", "design.beta")),
    (0.5, 0.5, ("design.alpha", "design.beta")),      # beta = alpha: no descent either
    ({"min": 0.5, "max": 0.6}, {"min": 0.2, "max": 0.4}, ("design.alpha.min", "design.beta.max")),
])
def test_beta_never_beyond_alpha_with_a_free_variable_is_bad_input_naming_both(tmp_path, alpha,
                                                                              beta, keys):
    # a periodic handover needs beta > alpha (docs/spec.md); with link_length free the
    # optimizer can move neither angle: no design it may choose has one
    data = robust_data(alpha=alpha, beta=beta, link_length={"min": 1.0, "max": 3.0})
    data.pop("expect", None)
    code, out, err = run("optimize", write(tmp_path, data))
    assert code == 2 and out == "" and "Traceback" not in err
    assert err.startswith(f"error: {tmp_path / 'spec.toml'}: {keys[0]} and {keys[1]}: expected "
                          "a handover angle beta above the back-stop angle alpha")



def test_a_guess_with_beta_below_a_fixed_alpha_is_no_solver_error(tmp_path):
    # beta's guess, the middle of [0.2, 0.55], is below alpha = 0.5: no closed form is defined
    # there, and every start moved toward it ended IPOPT at once (Invalid_Number_Detected)
    data = robust_data(alpha=0.5, beta={"min": 0.2, "max": 0.55},
                       link_length={"min": 1.0, "max": 3.0})
    data.pop("expect", None)
    code, out, err = run("optimize", write(tmp_path, data), "--format", "json", "--no-verify")
    doc = json.loads(out)
    assert doc["status"] == "infeasible" and code == 1 and doc["violations"]
    assert doc["design"]["beta"] > 0.5  # the least-violation design has a handover


# ------------------------------------------------------------------ friction on the stairs

def test_a_staircases_friction_tolerance_is_on_its_treads_and_the_step(tmp_path):
    from pdm_design.sheet import sheet_for
    from pdm_design.sheet.build import allocated_entries
    from pdm_design.sheet.parts import parts_list, tolerance_entries

    data = tomllib.loads((PROBLEMS / "paper_stairs_friction.toml").read_text())
    data["tolerances"] = {"friction": {"value": 0.02, "applies_to": "lot"}}
    sheet = sheet_for(write(tmp_path, data), tolerance=False)
    (entry,) = [e for e in tolerance_entries(sheet) if e.quantity.startswith("friction")]
    assert "palm" not in entry.applies_to and entry.applies_to.startswith("every tread's surface")
    parts, other = parts_list(sheet)
    step = next(p for p in parts if p.name == "step")
    assert [e.quantity for e in step.tolerances] == ["friction (spec)"] and other == ()
    # an allocated friction (optimize's tolerance list) is on the treads too, a palm's on a row
    allocated = {"quantity": "friction", "applies_to": "lot", "value": 0.02, "unit": "1",
                 "allocated": True, "limited_by": []}
    assert allocated_entries([allocated], kind="stairs")[0].applies_to.startswith("every tread's")
    entry = allocated_entries([allocated], kind="manipulators")[0]
    assert entry.applies_to.startswith("every palm's surface")


# ------------------------------------------------------------------ the sensitivity line

def test_the_sensitivity_line_is_sorted_with_its_intervals_and_says_what_is_not_resolved(
        tmp_path):
    import dataclasses

    from pdm_design.commands.yield_ import yield_text
    from pdm_design.spec import load_spec
    from pdm_design.tolerances.yield_ import yield_of

    spec = load_spec(_one_tolerance_spec(tmp_path, "stairs_yield.toml",
                                         {"rise": {"value": 0.005, "applies_to": "each"}}))
    result = yield_of(spec.scene, spec.design_at(), spec.tolerances, builds=16, stages=2,
                      confirm=1, scales=(), sensitivity_samples=0)
    rows = ({"quantity": "tread", "index": 0.10, "first": 0.02, "confidence": 0.15},   # 0 inside
            {"quantity": "launch_speed", "index": 0.62, "first": 0.5, "confidence": 0.2},
            {"quantity": "restitution", "index": 0.004, "first": 0.0, "confidence": 0.001},
            {"quantity": "rise", "index": 0.25, "first": 0.2, "confidence": 0.25})     # = width
    text = yield_text(dataclasses.replace(result, sensitivity=rows), "stairs")
    (line,) = [s for s in text.splitlines() if s.startswith("sensitivity")]
    body = line.split(": ", 1)[1]
    unresolved = " (not resolved by the builds drawn: its 95 % interval includes 0)"
    assert body == ("launch_speed 0.62 +- 0.2, rise 0.25 +- 0.25" + unresolved
                    + ", tread 0.1 +- 0.15" + unresolved + ", restitution 0.004 +- 0.001")


# ------------------------------------------------------------------ labels inside the page

LONG_PALM = (("palm mass (spec)", "every palm", 0.002, "kg", "the spec's statistical tolerance"),
             ("friction (spec)", "every palm's surface (one lot)", 0.05, "",
              "the spec's statistical tolerance"),
             ("link length (spec)", "every link", 0.0005, "m", "the spec's"))


def _outside_the_page(figure):
    """The drawn texts whose extents (the figure's renderer) leave the page, with them."""
    from matplotlib.text import Text

    from pdm_design.sheet.labels import figure_texts

    figure.draw_without_rendering()  # the positions of this page as drawn, at its dpi
    renderer, page = figure.canvas.get_renderer(), figure.bbox
    out = []
    for text in figure_texts(figure):
        box = Text.get_window_extent(text, renderer)
        if box.x0 < page.x0 or box.y0 < page.y0 or box.x1 > page.x1 or box.y1 > page.y1:
            out.append((text.get_text(), round(box.x0), round(box.x1)))
    return out


@pytest.mark.parametrize("tol", [None, {"dx": 0.08, "dy": 0.08}])
def test_every_label_of_every_pdf_page_of_a_30_row_is_inside_the_page(tol):
    import dataclasses

    from pdm_design.sheet import make_sheet
    from pdm_design.sheet.drawing import PAGE_ITEMS, draw
    from pdm_design.sheet.labels import overlapping_texts
    from pdm_design.sheet.parts import ToleranceEntry
    from pdm_design.spec import load_spec

    spec = load_spec(PROBLEMS / "paper_manipulators.toml")
    sheet = dataclasses.replace(make_sheet(spec, "evaluated", tol, "given here", 30),
                                tolerances=tuple(ToleranceEntry(*e) for e in LONG_PALM))
    pages = [draw(sheet)] + [draw(sheet, first, min(first + PAGE_ITEMS - 1, 30), notes=False)
                             for first in range(1, 31, PAGE_ITEMS)]  # the PDF's pages
    for number, page in enumerate(pages, start=1):
        assert _outside_the_page(page) == [], number
        assert overlapping_texts(page) == [], number
