"""The manipulators' drawing (sheet/drawing.py): millimetres, angles in degrees."""

from __future__ import annotations

import math

from ...sheet.labels import dimension
from ...sheet.parts import MM, nominal_run, part_of, tolerance_entries
from .sheet import PART_WORDS, hole_spacing, link_holes


def draw_manipulators(ax, labels, sheet, items, detail=True):
    """detail: dimension the first manipulator drawn (its link, angles, pivot and palm)."""
    from matplotlib.patches import Rectangle

    d, scene = sheet.design, sheet.spec.scene
    a, b, l = d["alpha"], d["beta"], d["link_length"]
    palm = scene.palm
    s = hole_spacing(sheet)
    for item in items:
        x, y = item["pivot_x_m"], item["pivot_y_m"]
        for theta, style in ((-a, {"color": "black", "lw": 1.1}),
                             (b, {"color": "tab:blue", "lw": 0.7, "ls": "--"})):
            for bracket, hole in link_holes((x, y), theta, l, s, palm.thickness):
                ax.plot([bracket[0] * MM, hole[0] * MM], [bracket[1] * MM, hole[1] * MM],
                        **style)
            cx, cy = x + l * math.sin(theta), y + l * math.cos(theta)
            solid = theta == -a
            ax.add_patch(Rectangle(((cx - palm.width / 2) * MM, (cy - palm.thickness) * MM),
                                   palm.width * MM, palm.thickness * MM, fill=solid,
                                   facecolor="0.75", edgecolor=style["color"], lw=0.7,
                                   ls="-" if solid else "--"))
        for angle in (-a, palm.front_stop):
            ax.plot([x * MM, (x + 0.25 * l * math.sin(angle)) * MM],
                    [y * MM, (y + 0.25 * l * math.cos(angle)) * MM], color="tab:red", lw=0.9)
        ax.plot([x * MM], [y * MM], marker="o", color="black", markersize=4)
        tx, ty = item["pivot_x_tolerance_m"], item["pivot_y_tolerance_m"]
        if tx is not None and ty is not None:
            ax.add_patch(Rectangle(((x - tx) * MM, (y - ty) * MM), 2 * tx * MM, 2 * ty * MM,
                                   fill=False, edgecolor="tab:red", lw=0.8))
        if item["manipulator"] < sheet.count:
            hx, hy = x + l * math.sin(b), y + l * math.cos(b)
            ax.plot([hx * MM], [hy * MM], marker="*", color="tab:orange", markersize=8)
    _path(ax, sheet, items)
    if detail:
        _first_dimensions(ax, labels, sheet, items[0])
    if detail and len(items) > 1:  # a longer view: too small to read; the parts list has it
        _pitch(ax, labels, items[0], items[1], l)
    if items[0]["manipulator"] == 1:
        _feed(ax, labels, sheet, items[0])
    for item in items:  # numbers last: the first to give way
        labels.add(ax, str(item["manipulator"]), (item["pivot_x_m"] * MM,
                   item["pivot_y_m"] * MM), (9, -9), optional=True)


def _by_part(sheet) -> dict[str, str]:
    """{part name: its tolerances in words} (sheet/parts.py)."""
    out: dict[str, list[str]] = {}
    for entry in tolerance_entries(sheet):
        out.setdefault(part_of(entry, PART_WORDS) or "", []).append(
            f"{entry.quantity} {entry.shown()}")
    return {part: "; ".join(words) for part, words in out.items()}


def _first_dimensions(ax, labels, sheet, item):
    """On the first manipulator drawn: the link length along its rear link, the angles, the
    pivot with its tolerance, the palm with its size and mass."""
    d, palm = sheet.design, sheet.spec.scene.palm
    a, b, l, fs = d["alpha"], d["beta"], d["link_length"], palm.front_stop
    x, y = item["pivot_x_m"], item["pivot_y_m"]
    tol = _by_part(sheet)
    (bracket, hole), _ = link_holes((x, y), -a, l, hole_spacing(sheet), palm.thickness)
    extra = f", {tol['link']}" if tol.get("link") else ""
    dimension(ax, labels, (bracket[0] * MM, bracket[1] * MM), (hole[0] * MM, hole[1] * MM),
              f"link l = {l * MM:.1f} mm{extra}", offset=0.08 * l * MM, side=1.0)
    from matplotlib.patches import Arc

    px, py = x * MM, y * MM
    for angle, radius, color in ((-a, 0.55, "black"), (b, 0.45, "tab:blue"),
                                 (fs, 0.3, "tab:red")):
        lo, hi = sorted((90.0, 90.0 - math.degrees(angle)))
        ax.add_patch(Arc((px, py), radius * l * MM, radius * l * MM, theta1=lo, theta2=hi,
                         color=color, lw=0.7))
    ax.plot([px, px], [py, py + 0.6 * l * MM], color="0.5", lw=0.5, ls=":")
    words = [(-a, 0.55, "black", f"back stop {math.degrees(-a):.2f} deg", "back stop"),
             (b, 0.45, "tab:blue", f"handover beta {math.degrees(b):.2f} deg", ""),
             (fs, 0.3, "tab:red", f"front stop {math.degrees(fs):.2f} deg", "front stop")]
    for angle, radius, color, text, part in words:
        half = angle / 2
        at = (px + radius / 2 * l * MM * math.sin(half), py + radius / 2 * l * MM * math.cos(half))
        more = f", {tol[part]}" if tol.get(part) else ""
        labels.add(ax, text + more, at, (60 * math.copysign(1, angle), 14), line=True,
                   color=color)
    pivot = f"pivot {item['manipulator']} ({px:.1f}, {py:.1f}) mm"
    # the placement box holds for the first verification.stages pivots only
    placed = tol.get("pivot bracket") if item["pivot_x_tolerance_m"] is not None else None
    if placed:
        pivot += f"\n{placed}"
    labels.add(ax, pivot, (px, py), (0, -26), line=True,
               color="tab:red" if placed else "black")
    cx, cy = (x + l * math.sin(-a)) * MM, (y + l * math.cos(-a)) * MM
    mass = sheet.spec.scene.body.mass / d["mass_ratio"]
    more = f",\n{tol['palm']}" if tol.get("palm") else ""  # a line of its own: a narrower label
    labels.add(ax, f"palm {palm.width * MM:.0f} x {palm.thickness * MM:.0f} mm, "
               f"{mass:.4g} kg{more}", (cx - palm.width * MM / 2, cy), (-10, 10), ha="right",
               line=True)


def _pitch(ax, labels, first, second, l):
    x1, y1 = first["pivot_x_m"] * MM, first["pivot_y_m"] * MM
    x2, y2 = second["pivot_x_m"] * MM, second["pivot_y_m"] * MM
    below = min(y1, y2) - 0.2 * l * MM
    dimension(ax, labels, (x1, below), (x2, below), f"pitch x {x2 - x1:.1f} mm", side=-1.0)
    ax.plot([x1, x1], [y1, below], color="0.55", lw=0.5, ls=":")
    ax.plot([x2, x2], [y2, below], color="0.55", lw=0.5, ls=":")
    side = x2 + 0.12 * l * MM
    dimension(ax, labels, (side, y2), (side, y1), f"pitch y {y1 - y2:.1f} mm", side=-1.0)
    ax.plot([x1, side], [y1, y1], color="0.55", lw=0.5, ls=":")


def _feed(ax, labels, sheet, first):
    """The start position, dimensioned from pivot 1, and the start velocity."""
    (sx, sy), (vx, vy) = sheet.spec.scene.initial.position, sheet.spec.scene.initial.velocity
    l = sheet.design["link_length"]
    x1, y1 = first["pivot_x_m"] * MM, first["pivot_y_m"] * MM
    sx, sy = sx * MM, sy * MM
    ax.plot([sx], [sy], marker="s", color="tab:green", markersize=5)
    speed = math.hypot(vx, vy)
    if speed > 0:
        arrow = 0.3 * l * MM / speed
        ax.annotate("", xy=(sx + vx * arrow, sy + vy * arrow), xytext=(sx, sy),
                    arrowprops={"arrowstyle": "->", "lw": 1.0, "color": "tab:green"})
    labels.add(ax, f"feed: start ({sx:.1f}, {sy:.1f}) mm, velocity ({vx * MM:.1f}, "
               f"{vy * MM:.1f}) mm/s", (sx, sy), (0, 22), color="tab:green", line=True)
    top = sy + 0.1 * l * MM
    if abs(x1 - sx) > 1e-9:
        dimension(ax, labels, (sx, top), (x1, top), f"{abs(x1 - sx):.1f} mm", color="tab:green")
        ax.plot([x1, x1], [y1, top], color="0.55", lw=0.5, ls=":")
    left = sx - 0.1 * l * MM
    if abs(y1 - sy) > 1e-9:
        dimension(ax, labels, (left, min(y1, sy)), (left, max(y1, sy)),
                  f"{abs(sy - y1):.1f} mm", color="tab:green")
        ax.plot([left, x1], [y1, y1], color="0.55", lw=0.5, ls=":")


def _path(ax, sheet, items):
    """The object's bottom-centre path as simulated, where it passes the items drawn."""
    run = nominal_run(sheet)
    if run is None or not run.trajectory.get("x"):
        return
    lo = items[0]["pivot_x_m"] - 1.5 * sheet.design["link_length"]
    hi = items[-1]["pivot_x_m"] + 1.5 * sheet.design["link_length"]
    shown = [(x * MM, y * MM) for x, y in zip(run.trajectory["x"], run.trajectory["y"])
             if lo <= x <= hi]
    if shown:
        ax.plot(*zip(*shown), color="tab:green", lw=0.9, ls=":")
