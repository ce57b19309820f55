"""The dimensioned drawing of a build sheet (matplotlib Figure + Agg canvas; no pyplot state).

Manipulators: every pivot with its tolerance box (to scale), the links and palms at the back stop
(-alpha, solid) and at the handover angle beta (dashed), the handover points, the object's path
as simulated, and dimension lines for the pitch (x and y), the link length and the angles.
Stairs: the staircase with rise and tread dimensions and tolerances, and the ball's path as
simulated. At most MAX_DRAWN manipulators or steps are drawn; the CSV lists all.
"""

from __future__ import annotations

import math
import textwrap

from ..report.render import render_figure
from .build import BuildSheet

MAX_DRAWN = 8
DRAWING_FORMATS = ("png", "svg")
WARNING_WIDTH, WARNING_LINES = 110, 3  # characters a line, lines: the drawing's warning


def drawing_files(sheet: BuildSheet, stem: str = "sheet") -> dict[str, bytes]:
    """{file name: bytes}: the drawing as PNG and SVG."""
    figure = draw(sheet)
    return {f"{stem}.{fmt}": _render(figure, fmt) for fmt in DRAWING_FORMATS}


def draw(sheet: BuildSheet):
    from matplotlib.figure import Figure

    figure = Figure(figsize=(13, 7.5), layout="constrained")
    ax = figure.add_subplot()
    ax.set_aspect("equal")
    ax.grid(True, alpha=0.2)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    shown = min(sheet.count, MAX_DRAWN)
    more = f" (first {shown} of {sheet.count}; the CSV lists all)" if shown < sheet.count else ""
    name = sheet.spec.name or sheet.spec.source
    if sheet.kind == "manipulators":
        _manipulators(ax, sheet, shown)
        title = f"{name}: {sheet.count} manipulators{more}"
    else:
        _stairs(ax, sheet, shown)
        title = f"{name}: {sheet.count} steps{more}"
    if sheet.failures:  # the workshop sees it on the drawing too, not only in sheet.md
        warning = textwrap.wrap(f"DOES NOT WORK - DO NOT BUILD: {sheet.failures[0]}",
                                WARNING_WIDTH, max_lines=WARNING_LINES)
        figure.suptitle("\n".join([title, *warning]), color="tab:red", fontweight="bold")
    else:
        figure.suptitle(title)
    _fit(figure, ax)
    return figure


def _covered(sheet) -> str:
    """'pivots 1 to N only' when the tolerance holds for fewer than are listed, else ''."""
    if not sheet.tolerance or sheet.tolerance_covers >= sheet.count:
        return ""
    what = "pivots" if sheet.kind == "manipulators" else "steps"
    return f"{what} 1 to {sheet.tolerance_covers} only"


# --------------------------------------------------------------------------- manipulators

def _manipulators(ax, sheet, shown):
    from matplotlib.patches import Arc, Rectangle

    spec, d = sheet.spec, sheet.design
    a, b, l = d["alpha"], d["beta"], d["link_length"]
    palm, body = spec.scene.palm, spec.scene.body
    items = sheet.items[:shown]
    for item in items:
        x, y = item["pivot_x_m"], item["pivot_y_m"]
        rest = (item["palm_at_back_stop_x_m"], item["palm_at_back_stop_y_m"])
        hand = (item["handover_x_m"], item["handover_y_m"])
        ax.plot([x, rest[0]], [y, rest[1]], color="black", lw=1.6)
        ax.plot([x, hand[0]], [y, hand[1]], color="tab:blue", lw=1.0, ls="--")
        ax.add_patch(Rectangle((rest[0] - palm.width / 2, rest[1] - palm.thickness),
                               palm.width, palm.thickness, facecolor="0.75",
                               edgecolor="black", lw=0.8))
        ax.add_patch(Rectangle((hand[0] - palm.width / 2, hand[1] - palm.thickness),
                               palm.width, palm.thickness, fill=False, edgecolor="tab:blue",
                               lw=0.8, ls="--"))
        ax.plot([x], [y], marker="o", color="black", markersize=5)
        tx, ty = item["pivot_x_tolerance_m"], item["pivot_y_tolerance_m"]
        if tx:
            ax.add_patch(Rectangle((x - tx, y - ty), 2 * tx, 2 * ty, fill=False,
                                   edgecolor="tab:red", lw=0.8))
        ax.annotate(str(item["manipulator"]), (x, y), xytext=(6, -12),
                    textcoords="offset points", fontsize=8)
        if item["manipulator"] < sheet.count:
            ax.plot([hand[0]], [hand[1]], marker="*", color="tab:orange", markersize=9)
    _object_path(ax, sheet, shown)
    first = items[0]
    x1, y1 = first["pivot_x_m"], first["pivot_y_m"]
    # the object resting on palm 1 where it first lands
    land = sheet.geometry.get("landing_offset") or 0.0
    rx, ry = first["palm_at_back_stop_x_m"], first["palm_at_back_stop_y_m"]
    ax.add_patch(Rectangle((rx + land - body.width / 2, ry), body.width, body.height,
                           facecolor="tab:green", alpha=0.5, edgecolor="tab:green"))
    # dimensions: link length, angles, pitch
    _dimension(ax, (x1, y1), (rx, ry), f"l = {l:.4g} m", offset=0.15 * l)
    ax.add_patch(Arc((x1, y1), 0.5 * l, 0.5 * l, theta1=90, theta2=90 + math.degrees(a),
                     color="black", lw=0.8))
    ax.add_patch(Arc((x1, y1), 0.4 * l, 0.4 * l, theta1=90 - math.degrees(b), theta2=90,
                     color="tab:blue", lw=0.8))
    ax.plot([x1, x1], [y1, y1 + 0.3 * l], color="0.5", lw=0.6, ls=":")
    ax.annotate(f"back stop -alpha = -{a:.4g} rad", (x1 - 0.25 * l * math.sin(a / 2),
                y1 + 0.25 * l), xytext=(-150, 10), textcoords="offset points", fontsize=8,
                arrowprops={"arrowstyle": "-", "lw": 0.5})
    ax.annotate(f"handover beta = {b:.4g} rad", (x1 + 0.2 * l * math.sin(b / 2),
                y1 + 0.2 * l * math.cos(b / 2)), xytext=(30, 25),
                textcoords="offset points", fontsize=8, color="tab:blue",
                arrowprops={"arrowstyle": "-", "lw": 0.5, "color": "tab:blue"})
    if len(items) > 1:
        x2, y2 = items[1]["pivot_x_m"], items[1]["pivot_y_m"]
        below = min(y1, y2) - 0.25 * l
        _dimension(ax, (x1, below), (x2, below), f"pitch x = {x2 - x1:.5g} m", offset=0.0)
        ax.plot([x1, x1], [y1, below], color="0.5", lw=0.5, ls=":")
        ax.plot([x2, x2], [y2, below], color="0.5", lw=0.5, ls=":")
        side = x2 + 0.15 * l
        _dimension(ax, (side, y1), (side, y2), f"pitch y = {y1 - y2:.4g} m", offset=0.0)
        ax.plot([x1, side], [y1, y1], color="0.5", lw=0.5, ls=":")
    tol = sheet.tolerance
    if tol and max(tol["dx"], tol["dy"]) > 0.0:  # a zero box has nothing to zoom in on
        _tolerance_inset(ax, x1, y1, tol)
    where = _covered(sheet) or "the same at every pivot"
    text = (f"red box (inset; {where}): pivot tolerance "
            f"+-{tol['dx'] * 1e3:.3g} mm (x), +-{tol['dy'] * 1e3:.3g} mm (y)" if tol else
            "pivot tolerance: " + sheet.tolerance_note)
    legend = ("solid: links and palms at the back stop; dashed: at the handover angle; "
              "stars: handover points; dotted: the object's path (simulated)")
    ax.text(0.01, 0.01, text + "\n" + legend, transform=ax.transAxes, fontsize=8,
            va="bottom")
    ax.autoscale_view()
    x_lo, x_hi = ax.get_xlim()
    y_lo, y_hi = ax.get_ylim()
    ax.set_ylim(y_lo - 0.15 * (y_hi - y_lo), y_hi)


def _tolerance_inset(ax, x, y, tol):
    """A zoomed view of pivot 1 and the box it may be placed within."""
    from matplotlib.patches import Rectangle

    tx, ty = tol["dx"], tol["dy"]
    inset = ax.inset_axes([0.80, 0.62, 0.18, 0.33])
    inset.add_patch(Rectangle((-tx * 1e3, -ty * 1e3), 2e3 * tx, 2e3 * ty, fill=False,
                              edgecolor="tab:red", lw=1.0))
    inset.plot([0], [0], marker="o", color="black")
    span = 1.6e3 * max(tx, ty)
    inset.set_xlim(-span, span)
    inset.set_ylim(-span, span)
    inset.set_aspect("equal")
    inset.tick_params(labelsize=6)
    inset.set_title(f"pivot tolerance box (mm), about ({x:.4g}, {y:.4g}) m", fontsize=7)
    inset.annotate(f"+-{tx * 1e3:.3g}", (tx * 1e3, 0), xytext=(3, 0),
                   textcoords="offset points", fontsize=6, va="center")
    inset.annotate(f"+-{ty * 1e3:.3g}", (0, ty * 1e3), xytext=(0, 3),
                   textcoords="offset points", fontsize=6, ha="center")


def _object_path(ax, sheet, shown):
    """The object's bottom-centre path from the simulator (as far as it got)."""
    try:
        from ..verify import simulate_spec

        result = simulate_spec(sheet.spec, sheet.spec.design_at(), stages=shown,
                               record_trajectory=True)
    except Exception:  # the drawing does not need the path to be useful
        return
    t = result.trajectory
    if t.get("x"):
        ax.plot(t["x"], t["y"], color="tab:green", lw=0.9, ls=":")
        x0, y0 = sheet.spec.scene.initial.position
        ax.plot([x0], [y0], marker="s", color="tab:green", markersize=5)
        ax.annotate("start", (x0, y0), xytext=(5, 5), textcoords="offset points", fontsize=8)


# --------------------------------------------------------------------------- stairs

def _stairs(ax, sheet, shown):
    from matplotlib.patches import Circle, Polygon

    items = sheet.items[:shown]
    first = items[0]
    rise0 = first["rise_m"]
    x_start = min(0.0, first["back_x_m"]) - 0.3 * first["tread_m"]
    outline = [(x_start, rise0), (first["back_x_m"], rise0)]
    for item in items:
        outline += [(item["back_x_m"], item["level_m"]), (item["nose_x_m"], item["level_m"])]
    last = items[-1]
    bottom = last["level_m"] - 0.5 * max(rise0, 0.1 * first["tread_m"])
    outline += [(last["nose_x_m"], bottom), (x_start, bottom)]
    ax.add_patch(Polygon(outline, closed=True, facecolor="0.85", edgecolor="black", lw=1.2))
    r = sheet.spec.scene.ball.radius
    # the ball's path (simulated): centre = lowest point + r
    try:
        from ..verify import simulate_spec

        result = simulate_spec(sheet.spec, sheet.spec.design_at(), stages=shown,
                               record_trajectory=True)
        t = result.trajectory
        ax.plot(t["x"], [y + r for y in t["y"]], color="tab:blue", lw=0.9, ls="--")
        for stage in result.stages:
            if r > 0:
                ax.add_patch(Circle((stage["x"], stage["y"] + r), r, fill=False,
                                    edgecolor="tab:blue", lw=0.6))
            else:
                ax.plot([stage["x"]], [stage["y"]], marker="o", color="tab:blue", ms=3)
    except Exception:  # the drawing does not need the path to be useful
        pass
    h0 = sheet.spec.scene.initial.drop_height
    ax.plot([0.0], [h0 + r], marker="s", color="tab:blue", markersize=5)
    ax.annotate(f"launch {sheet.design['launch_speed']:.4g} m/s", (0.0, h0 + r),
                xytext=(5, 6), textcoords="offset points", fontsize=8)
    tread, rise = first["tread_m"], first["rise_m"]
    tol_r, tol_t = first["rise_tolerance_m"], first["tread_tolerance_m"]
    tr = f" +-{tol_r * 1e3:.3g} mm" if tol_r is not None else ""
    tt = f" +-{tol_t * 1e3:.3g} mm" if tol_t is not None else ""
    dim = items[1] if len(items) > 1 else first   # dimensions drawn inside the solid
    depth = 0.45 * max(dim["rise_m"], 0.1 * tread)
    _dimension(ax, (dim["back_x_m"], dim["level_m"] - depth),
               (dim["nose_x_m"], dim["level_m"] - depth), f"tread {tread:.4g} m{tt}",
               below=True)
    if len(items) > 3:  # on the riser below tread 3, clear of the tread dimension
        upper, riser = items[2], items[3]
        x = riser["back_x_m"] - 0.04 * tread
        _dimension(ax, (x, riser["level_m"]), (x, upper["level_m"]), f"rise {rise:.4g} m{tr}",
                   left=True)
    for item in items:
        ax.annotate(str(item["step"]), (item["back_x_m"], item["level_m"]), xytext=(4, 3),
                    textcoords="offset points", fontsize=8, ha="left", va="bottom")
    limit = _covered(sheet)
    ax.text(0.99, 0.99, f"every step: rise {rise:.5g} m{tr}, tread {tread:.5g} m{tt}"
            + (f"; tolerances for {limit}" if limit else "") + "\n"
            "dashed: the ball's centre (simulated)", transform=ax.transAxes, fontsize=8,
            ha="right", va="top")
    ax.autoscale_view()


def _fit(figure, ax, width=13.0):
    """Figure height to suit the drawing's aspect (equal scales on x and y)."""
    x_lo, x_hi = ax.get_xlim()
    y_lo, y_hi = ax.get_ylim()
    ratio = (y_hi - y_lo) / max(x_hi - x_lo, 1e-12)
    figure.set_size_inches(width, min(max(width * ratio + 1.2, 4.0), 10.0))


# --------------------------------------------------------------------------- helpers

def _dimension(ax, p, q, label, *, offset=0.0, below=False, left=False):
    """A dimension line from p to q (shifted `offset` along its normal), arrows both ends."""
    (x1, y1), (x2, y2) = p, q
    length = math.hypot(x2 - x1, y2 - y1) or 1.0
    nx, ny = -(y2 - y1) / length, (x2 - x1) / length
    a = (x1 + nx * offset, y1 + ny * offset)
    b = (x2 + nx * offset, y2 + ny * offset)
    ax.annotate("", xy=b, xytext=a, arrowprops={"arrowstyle": "<->", "lw": 0.8,
                                                 "shrinkA": 0, "shrinkB": 0})
    mid = ((a[0] + b[0]) / 2, (a[1] + b[1]) / 2)
    vertical = abs(x2 - x1) < 1e-12 * length
    if vertical:
        ax.annotate(label, mid, xytext=(-6 if left else 6, 0), textcoords="offset points",
                    fontsize=8, ha="right" if left else "left", va="center")
    else:
        ax.annotate(label, mid, xytext=(0, -4 if below else 4), textcoords="offset points",
                    fontsize=8, ha="center", va="top" if below else "bottom")


def _render(figure, fmt: str) -> bytes:
    return render_figure(figure, fmt, dpi=120)
