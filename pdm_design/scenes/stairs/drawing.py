"""The staircase's drawing (sheet/drawing.py): millimetres."""

from __future__ import annotations

from ...sheet.labels import dimension
from ...sheet.parts import MM, nominal_run


def draw_stairs(ax, labels, sheet, items, detail=True):
    """detail: dimension a step's tread and rise."""
    from matplotlib.patches import Circle, Polygon

    first, last = items[0], items[-1]
    rise0, tread0 = first["rise_m"] * MM, first["tread_m"] * MM
    start = first["step"] == 1
    top = first["level_m"] * MM + rise0
    left = (min(0.0, first["back_x_m"]) * MM - 0.3 * tread0) if start else first["back_x_m"] * MM
    outline = [(left, top), (first["back_x_m"] * MM, top)]
    for item in items:
        outline += [(item["back_x_m"] * MM, item["level_m"] * MM),
                    (item["nose_x_m"] * MM, item["level_m"] * MM)]
    bottom = last["level_m"] * MM - 0.6 * max(rise0, 0.1 * tread0)
    outline += [(last["nose_x_m"] * MM, bottom), (left, bottom)]
    ax.add_patch(Polygon(outline, closed=True, facecolor="0.85", edgecolor="black", lw=1.1))
    r = sheet.spec.scene.ball.radius * MM
    run = nominal_run(sheet)
    path = [] if run is None else [(x * MM, y * MM) for x, y in zip(run.trajectory["x"],
                                                                   run.trajectory["y"])]
    impacts = [] if run is None else [(s["x"] * MM, s["y"] * MM) for s in run.stages]
    lo, hi = left - tread0, last["nose_x_m"] * MM + tread0
    shown = [(x, y + r) for x, y in path if lo <= x <= hi]
    if shown:
        ax.plot(*zip(*shown), color="tab:blue", lw=0.9, ls="--")
    for x, y in impacts:
        if lo <= x <= hi and r > 0:
            ax.add_patch(Circle((x, y + r), r, fill=False, edgecolor="tab:blue", lw=0.6))
    tol = {e: first[f"{e}_tolerance_m"] for e in ("rise", "tread")}
    more = {k: (f" +-{v * MM:.3g} mm" if v is not None else "") for k, v in tol.items()}
    dim = items[1] if len(items) > 1 else first
    depth = dim["level_m"] * MM - 0.3 * max(dim["rise_m"] * MM, 0.1 * tread0)
    if detail:
        dimension(ax, labels, (dim["back_x_m"] * MM, depth), (dim["nose_x_m"] * MM, depth),
                  f"tread {tread0:.1f} mm{more['tread']}", side=-1.0)
    if detail and len(items) > 2:  # the riser of the third step drawn, beside it
        upper, riser = items[1], items[2]
        x = riser["back_x_m"] * MM - 0.05 * tread0
        dimension(ax, labels, (x, riser["level_m"] * MM), (x, upper["level_m"] * MM),
                  f"rise {rise0:.1f} mm{more['rise']}", side=1.0)
    if start:
        _feed(ax, labels, sheet, first, r, left)
    for item in items:  # numbers last: the first to give way
        labels.add(ax, str(item["step"]), (item["back_x_m"] * MM, item["level_m"] * MM),
                   (8, 7), optional=True)


def _feed(ax, labels, sheet, first, r, left):
    """The launch: its speed, its height above tread 1 (dimensioned left of the staircase's
    wall, at x = left) and its distance to tread 1's back."""
    h0 = sheet.spec.scene.initial.drop_height * MM
    level = first["level_m"] * MM
    speed = sheet.design["launch_speed"] * MM
    tread = first["tread_m"] * MM
    ax.plot([0.0], [level + h0 + r], marker="s", color="tab:green", markersize=5)
    ax.annotate("", xy=(0.25 * tread, level + h0 + r), xytext=(0.0, level + h0 + r),
                arrowprops={"arrowstyle": "->", "lw": 1.0, "color": "tab:green"})
    labels.add(ax, f"feed: launch {speed:.1f} mm/s horizontally", (0.0, level + h0 + r),
               (0, 16), color="tab:green", ha="left")
    x = left - 0.1 * tread
    dimension(ax, labels, (x, level), (x, level + h0), f"{h0:.1f} mm above tread 1",
              color="tab:green", side=1.0)
    ax.plot([x, first["back_x_m"] * MM], [level, level], color="0.55", lw=0.5, ls=":")
    ax.plot([x, 0.0], [level + h0, level + h0], color="0.55", lw=0.5, ls=":")
    if abs(first["back_x_m"]) > 1e-12:
        y = level + h0 + r + 0.25 * max(h0, tread)
        dimension(ax, labels, (0.0, y), (first["back_x_m"] * MM, y),
                  f"{first['back_x_m'] * MM:.1f} mm to tread 1", color="tab:green")
