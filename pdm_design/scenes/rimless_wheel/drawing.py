"""The rimless wheel's drawing (sheet/drawing.py): the ramp or the stairs to scale with their
dimensions, the footholds numbered, the simulated hub path and the wheel at its start; mm."""

from __future__ import annotations

import math

from ...sheet.labels import dimension
from ...sheet.parts import MM, nominal_run
from .sheet import numbers, wheel_spokes


def draw_wheel_sheet(ax, labels, sheet, items, detail=True):
    """items: a slice of sheet.items; detail: dimension the ground (few enough to read)."""
    g = numbers(sheet.spec)
    start = items[0]["step"] == 1
    if g["stairs"]:
        _stairs(ax, labels, sheet, items, g, detail, start)
    else:
        _ramp(ax, labels, items, g, detail, start)
    _path(ax, sheet, items, g)
    if start:
        _wheel(ax, labels, sheet, g, detail)
    for item in items:  # numbers last: the first to give way
        labels.add(ax, str(item["step"]), _foot(item), (0, -10), optional=True)


def _foot(item):
    return item["foot_x_m"] * MM, item.get("foot_y_m", item.get("level_m", 0.0)) * MM


def _ramp(ax, labels, items, g, detail, start):
    from matplotlib.patches import Polygon

    beta, chord = g["slope"], g["chord"] * MM
    along = (items[0]["step"] - 1.5 if start else items[0]["step"] - 1) * chord
    end = (items[-1]["step"] + 0.5) * chord
    down = (math.cos(beta), -math.sin(beta))
    top = (along * down[0], along * down[1])
    bottom = (end * down[0], end * down[1])
    floor = min(top[1], bottom[1]) - 0.15 * g["leg"] * MM
    ax.add_patch(Polygon([top, bottom, (bottom[0], floor), (top[0], floor)], closed=True,
                         facecolor="0.85", edgecolor="black", lw=1.1))
    feet = [(0.0, 0.0)] if start else []
    feet += [_foot(i) for i in items]
    ax.plot(*zip(*feet), "o", color="black", markersize=3)
    if not detail:
        return
    tol = items[0]["slope_tolerance_rad"]
    more = f" +-{math.degrees(tol):.3g} deg" if tol is not None else ""
    a, b = (feet[0], feet[1]) if len(feet) > 1 else ((0.0, 0.0), feet[0])
    dimension(ax, labels, a, b, f"{chord:.2f} mm", offset=-0.12 * g["leg"] * MM, side=-1.0)
    corner = (top[0] + 0.3 * (bottom[0] - top[0]), top[1])  # the horizontal at the top
    ax.plot([top[0], corner[0]], [top[1], corner[1]], color="0.55", lw=0.5, ls=":")
    mid = (0.65 * bottom[0] + 0.35 * top[0], 0.65 * bottom[1] + 0.35 * top[1])
    labels.add(ax, f"slope {math.degrees(beta):.3f} deg{more}", mid, (0, 14))


def _stairs(ax, labels, sheet, items, g, detail, start):
    from matplotlib.patches import Polygon

    rise, tread, s0 = g["rise"] * MM, g["tread"] * MM, g["landing_offset"] * MM
    first, last = items[0], items[-1]
    outline = []
    if start:  # tread 0, where the wheel starts, its back s0 behind foothold 0
        outline += [(-s0 - 0.3 * tread, rise), (-s0, rise), (-s0, 0.0),
                    (first["back_x_m"] * MM, 0.0)]
    else:
        outline.append((first["back_x_m"] * MM, first["level_m"] * MM + rise))
    for item in items:
        outline += [(item["back_x_m"] * MM, item["level_m"] * MM),
                    (item["nose_x_m"] * MM, item["level_m"] * MM)]
    bottom = last["level_m"] * MM - 0.6 * max(rise, 0.1 * tread)
    outline += [(last["nose_x_m"] * MM, bottom), (outline[0][0], bottom)]
    ax.add_patch(Polygon(outline, closed=True, facecolor="0.85", edgecolor="black", lw=1.1))
    feet = [(0.0, 0.0)] if start else []
    ax.plot(*zip(*(feet + [_foot(i) for i in items])), "o", color="black", markersize=3)
    if not detail:
        return
    more = {e: (f" +-{first[f'{e}_tolerance_m'] * MM:.3g} mm"
                if first[f"{e}_tolerance_m"] is not None else "") for e in ("rise", "tread")}
    dim = items[1] if len(items) > 1 else first  # clear of the rise beside the first
    depth = dim["level_m"] * MM - 0.3 * max(rise, 0.1 * tread)
    dimension(ax, labels, (dim["back_x_m"] * MM, depth), (dim["nose_x_m"] * MM, depth),
              f"tread {tread:.2f} mm{more['tread']}", side=-1.0)
    x = first["back_x_m"] * MM - 0.05 * tread
    dimension(ax, labels, (x, first["level_m"] * MM), (x, first["level_m"] * MM + rise),
              f"rise {rise:.2f} mm{more['rise']}", side=1.0)
    if start:
        y = 0.35 * max(rise, 0.1 * tread)
        dimension(ax, labels, (-s0, -y), (0.0, -y), f"{s0:.2f} mm to foothold 0", side=-1.0,
                  color="tab:green")


def _path(ax, sheet, items, g):
    """The hub's simulated path over the items drawn (dotted)."""
    run = nominal_run(sheet)
    if run is None or not run.trajectory.get("x"):
        return
    lo = (items[0]["foot_x_m"] - 1.5 * g["chord"]) * MM
    hi = (items[-1]["foot_x_m"] + 0.5 * g["chord"]) * MM
    shown = [(x * MM, y * MM) for x, y in zip(run.trajectory["x"], run.trajectory["y"])
             if lo <= x * MM <= hi]
    if shown:
        ax.plot(*zip(*shown), color="tab:green", lw=0.9, ls=":")


def _wheel(ax, labels, sheet, g, detail):
    """The wheel at its start: its spokes from the hub, spoke 0 on foothold 0."""
    from matplotlib.patches import Circle

    hub, tips = wheel_spokes(sheet.spec, g)
    for j, tip in enumerate(tips):
        ax.plot([hub[0], tip[0]], [hub[1], tip[1]], color="0.35" if j else "tab:blue",
                lw=1.4 if j == 0 else 1.0)
    shown = max(sheet.spec.scene.wheel.gyration * MM, 0.04 * g["leg"] * MM)
    ax.add_patch(Circle(hub, shown, facecolor="white", edgecolor="black", lw=1.0, zorder=3))
    w = sheet.spec.scene.wheel
    labels.add(ax, f"hub {w.mass * 1e3:.4g} g", hub, (0, 14))
    if detail:
        j = g["n"] // 2  # the spoke pointing up: its length
        labels.add(ax, f"{g['n']} spokes of {g['leg'] * MM:.2f} mm, "
                       f"{math.degrees(2 * g['alpha']):.4g} deg apart",
                   tips[j], (0, 9), color="0.25")
