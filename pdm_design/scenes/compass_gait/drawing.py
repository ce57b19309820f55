"""The compass gait's drawing (sheet/drawing.py): millimetres. The ramp (or stairs) under the
drawn steps, the walker standing at the periodic gait's post-strike state on step 1's stance
foot (the origin), each step's stance foot numbered, the hip's simulated path; dimensioned: the
step length, the leg length, the centre of mass on the stance leg and the slope."""

from __future__ import annotations

import math

from ...sheet.labels import dimension
from ...sheet.parts import MM, nominal_run
from .sheet import pose, walker_of


def draw_walker(ax, labels, sheet, items, detail=True):
    from matplotlib.patches import Polygon

    walker, design = walker_of(sheet.spec), sheet.spec.design_at()
    l = walker.leg_length * MM
    body = pose(sheet.periodic["fixed_point"], walker.leg_length)
    hip, trailing = _mm(body.hip), _mm(body.trailing)
    adv = _mm(body.advance)
    feet = [(i["foot_x_m"] * MM, i["foot_y_m"] * MM) for i in items]
    start = items[0]["step"] == 1
    left = (min(feet[0][0], trailing[0]) - 0.3 * l) if start else feet[0][0] - 0.3 * l
    right = feet[-1][0] + adv[0] + 0.3 * l
    ax.add_patch(Polygon(ground_outline(design, feet[0], adv, left, right, l), closed=True,
                         facecolor="0.85", edgecolor="black", lw=1.1))
    _path(ax, sheet, left, right)
    for x, y in feet:
        ax.plot([x], [y], marker="o", color="black", markersize=3)
    if start:
        _walker(ax, labels, sheet, walker, hip, trailing, detail)
    if detail and len(feet) > 1:
        size = max(abs(adv[0]), abs(adv[1]), 1.0)
        dimension(ax, labels, feet[0], feet[1],
                  f"step {sheet.periodic['step_length'] * MM:.1f} mm", offset=-0.35 * size,
                  side=-1.0)
    if design.slope is not None and detail:
        labels.add(ax, f"slope {math.degrees(float(design.slope)):.2f} deg",
                   (feet[-1][0], feet[-1][1]), (0, -22), color="0.25")
    elif detail:
        labels.add(ax, f"stairs: rise {float(design.rise) * MM:.1f} mm, tread "
                       f"{float(design.tread) * MM:.1f} mm", feet[-1], (0, -22), color="0.25")
    for item, at in zip(items, feet):  # numbers last: the first to give way
        labels.add(ax, str(item["step"]), at, (8, 9), optional=True)


def _mm(point):
    return (point[0] * MM, point[1] * MM)


def ground_outline(design, foot, adv, left, right, l):
    """The ground's outline (mm): a ramp through the feet, or a tread under each foot."""
    if design.slope is not None:
        drop = math.tan(float(design.slope))
        top = [(x, foot[1] - (x - foot[0]) * drop) for x in (left, right)]
    else:
        rise, tread = float(design.rise) * MM, float(design.tread) * MM
        behind = math.ceil((foot[0] - 0.5 * tread - left) / tread)  # treads left of foot 1's
        x, y = foot[0] + (0.5 - behind) * tread, foot[1] + behind * rise
        top = [(left, y)]
        while x < right:
            top += [(x, y), (x, y - rise)]
            x, y = x + tread, y - rise
        top.append((right, y))
    bottom = min(p[1] for p in top) - 0.25 * l
    return top + [(right, bottom), (left, bottom)]


def _path(ax, sheet, left, right):
    run = nominal_run(sheet)
    traj = {} if run is None else run.trajectory
    shown = [(x * MM, y * MM) for x, y in zip(traj.get("x", ()), traj.get("y", ()))
             if left <= x * MM <= right]
    if shown:
        ax.plot(*zip(*shown), color="tab:green", lw=0.9, ls=":")


def _walker(ax, labels, sheet, walker, hip, trailing, detail):
    """The legs (stance thick), the hip and the legs' centres of mass; dimensioned."""
    foot = (0.0, 0.0)
    ax.plot([foot[0], hip[0]], [foot[1], hip[1]], color="tab:blue", lw=3.0,
            solid_capstyle="round")
    ax.plot([trailing[0], hip[0]], [trailing[1], hip[1]], color="tab:blue", lw=1.6,
            solid_capstyle="round")
    l, b = walker.leg_length * MM, walker.leg_com * MM
    ax.plot([hip[0]], [hip[1]], marker="o", color="tab:red", markersize=9)
    for end in (foot, trailing):
        com = (hip[0] + (end[0] - hip[0]) * b / l, hip[1] + (end[1] - hip[1]) * b / l)
        ax.plot([com[0]], [com[1]], marker="o", color="tab:orange", markersize=5)
    fixed = sheet.periodic["fixed_point"]
    mass = "" if walker.model == "simplest" else f" {walker.hip_mass * 1e3:.0f} g"
    labels.add(ax, f"hip{mass}", hip, (0, 14), color="tab:red")
    if not detail:
        return
    labels.add(ax, f"stance {math.degrees(fixed['stance']):.2f} deg, swing "
                   f"{math.degrees(fixed['swing']):.2f} deg from vertical", hip, (0, 28),
               color="tab:blue")
    dimension(ax, labels, trailing, hip, f"leg {l:.1f} mm", offset=0.1 * l, side=1.0)
    if walker.model != "simplest":
        com = (hip[0] + (foot[0] - hip[0]) * b / l, hip[1] + (foot[1] - hip[1]) * b / l)
        dimension(ax, labels, hip, com, f"c.o.m. {b:.1f} mm", offset=0.1 * l, side=-1.0)
        behind = (hip[0] + (trailing[0] - hip[0]) * b / l,
                  hip[1] + (trailing[1] - hip[1]) * b / l)
        labels.add(ax, f"each leg {walker.leg_mass * 1e3:.0f} g", behind, (-40, 0),
                   color="tab:orange")
