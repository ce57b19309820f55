"""Design-table plots: one panel per distinct column, one x range, infeasible points in the
legend, lengths in millimetres."""

from pdm_design.sweep.grid import SweepAxis
from pdm_design.sweep.plots import _distinct, _figure, labels_of, sweep_figures

AXES = (SweepAxis("mass_ratio", ("design", "mass_ratio"), (2.0, 4.0, 6.0, 8.0)),)


def rows(statuses=("optimal",) * 4):
    out = []
    for q, status in zip(AXES[0].values, statuses):
        box = 0.01 * q  # a square box: tolerance = dx = dy
        out.append({"design.mass_ratio": str(q), "status": status, "tolerance": str(box),
                    "tolerance.dx": str(box), "tolerance.dy": str(box),
                    "min_margin": str(0.1 * q), "pitch_x": str(1.5 + 0.01 * q)})
    return out


def test_equal_columns_share_one_panel():
    groups = _distinct(rows(), ["tolerance", "tolerance.dx", "tolerance.dy", "min_margin"])
    assert groups == [["tolerance", "tolerance.dx", "tolerance.dy"], ["min_margin"]]
    uneven = rows()
    uneven[0]["tolerance.dy"] = "0.5"
    assert len(_distinct(uneven, ["tolerance", "tolerance.dx", "tolerance.dy"])) == 2


def test_panels_share_the_x_range_and_lengths_are_millimetres():
    figure = _figure(AXES, rows(), [["tolerance", "tolerance.dx"], ["min_margin"],
                                    ["pitch_x"]], "", "t", labels_of("manipulators"))
    shown = [ax for ax in figure.axes if ax.get_visible()]
    assert len(shown) == 3
    assert len({ax.get_xlim() for ax in shown}) == 1
    lo, hi = shown[0].get_xlim()
    assert lo < 2.0 and hi > 8.0
    assert shown[0].get_ylabel() == "tolerance (smallest half-width) = dx (mm)"
    assert list(shown[0].lines[0].get_ydata()) == [20.0, 40.0, 60.0, 80.0]  # 0.01 q m in mm
    assert shown[2].get_ylabel() == "pitch x (mm)"


def test_infeasible_points_are_in_the_legend():
    figure = _figure(AXES, rows(("optimal", "infeasible", "optimal", "optimal")),
                     [["tolerance"]], "", "t")
    texts = [t.get_text() for legend in figure.legends for t in legend.get_texts()]
    assert any(t.startswith("not a success") for t in texts)
    assert _figure(AXES, rows(), [["tolerance"]], "", "t").legends == []


def test_a_table_of_a_square_box_writes_both_figures():
    files = sweep_figures("manipulators", AXES, rows())
    assert set(files) == {"optimum.png", "optimum.svg", "tolerance.png", "tolerance.svg"}
    assert all(files[f"{name}.png"].startswith(b"\x89PNG") for name in ("optimum", "tolerance"))


def test_a_swept_length_is_drawn_in_millimetres_and_a_requirement_is_not():
    # the scene's columns say which keys are lengths (Scene.column_labels, unit "m"); a
    # requirement is a margin even where a column of its name is a length
    from pdm_design.sweep.plots import _x_axis

    def axis(*path):
        return SweepAxis(path[-1], path, (0.1, 0.2))

    assert _x_axis(axis("design", "link_length"), labels_of("manipulators")) == (
        "design.link_length (mm)", 1e3)
    assert _x_axis(axis("design", "rise"), labels_of("stairs"))[1] == 1e3
    assert _x_axis(axis("scene", "body", "width"), labels_of("stairs"))[1] == 1e3
    assert _x_axis(axis("requirements", "nose_clearance"), labels_of("stairs")) == (
        "requirements.nose_clearance", 1.0)
    assert _x_axis(axis("design", "mass_ratio"), labels_of("manipulators"))[1] == 1.0
