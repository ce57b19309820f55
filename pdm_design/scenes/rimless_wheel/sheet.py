"""The rimless wheel's build sheet (sheet/build.py): the ground as built, one item a step (the
foothold the step's spoke lands on), and the wheel's parts list.

Frame (as the simulator's, scenes/rimless_wheel/sim.py): x downhill, y up, foothold 0 (where
the wheel starts, its stance spoke at beta - alpha from the vertical) at the origin. On a ramp of
slope beta the footholds lie a chord 2 l sin(pi / n) apart along it, foothold k at
k chord (cos beta, -sin beta). On stairs tread k lies k rise below tread 0 and runs from its back
x = k tread - s0 to its nose x = (k + 1) tread - s0 (s0: landing_offset, foothold 0 from the back
of tread 0); foothold k is at x = k a, a = sqrt(chord^2 - rise^2) (docs/rimless_wheel.md,
section 7), s0 + k (a - tread) from the back of its tread.
"""

from __future__ import annotations

import math

from ...sheet.generic import SheetWords
from ...sheet.parts import MM, Part, ToleranceEntry, deg, mm

PART_WORDS = {"hub": ("hub", "mass", "gyration"),
              "spoke": ("spoke", "leg"),
              "spoke tip": ("tip", "friction"),
              "ramp": ("slope", "ramp"),
              "step": ("step", "rise", "tread", "stair")}
WORDS = SheetWords(item="foothold", units="millimetres, degrees",
                   legend="dotted: the hub's path (simulated); the wheel at its start, its "
                          "stance spoke (blue) on foothold 0; dots: the footholds, numbered by "
                          "the step that lands on each")


def numbers(spec) -> dict:
    """The design's ground and wheel in SI units: n, leg, alpha (half pitch), chord, and slope
    (a ramp) or rise, tread, landing_offset, advance (stairs)."""
    from .analysis import resolve

    wheel, geometry, _ = resolve(spec.scene, spec.design_at())
    out = {"n": wheel.n, "leg": wheel.leg, "alpha": wheel.alpha, "chord": wheel.chord,
           "beta": wheel.beta, "stairs": spec.scene.ground == "stairs"}
    if out["stairs"]:
        out.update(rise=geometry["rise"], tread=geometry["tread"],
                   landing_offset=geometry["landing_offset"],
                   advance=geometry["tread"] + geometry["drift_per_step"])
    else:
        out["slope"] = float(spec.design_at().slope)
    return out


def sheet_rows(spec, analysis, tol, count):
    g = numbers(spec)
    covered = spec.verification.stages
    tol = tol or {}

    def within(k, axis):
        return tol.get(axis) if k <= covered else None

    items = []
    for k in range(1, count + 1):
        if g["stairs"]:
            items.append({
                "step": k, "rise_m": g["rise"], "tread_m": g["tread"],
                "rise_tolerance_m": within(k, "rise"), "tread_tolerance_m": within(k, "tread"),
                "back_x_m": k * g["tread"] - g["landing_offset"],
                "nose_x_m": (k + 1) * g["tread"] - g["landing_offset"],
                "level_m": -k * g["rise"], "foot_x_m": k * g["advance"],
                "landing_from_back_m": g["landing_offset"] + k * (g["advance"] - g["tread"])})
        else:
            beta = g["slope"]
            items.append({
                "step": k, "slope_rad": beta, "slope_tolerance_rad": within(k, "slope"),
                "spacing_m": g["chord"], "along_ramp_m": k * g["chord"],
                "foot_x_m": k * g["chord"] * math.cos(beta),
                "foot_y_m": -k * g["chord"] * math.sin(beta)})
    return _summary(spec, analysis, g, tol, count), items


def _summary(spec, analysis, g, tol, count):
    w = spec.scene.wheel
    rows = [("steps", count, "", None), ("ground", spec.scene.ground, "", None)]
    if g["stairs"]:
        rows += [("rise (every step)", g["rise"], "m", tol.get("rise")),
                 ("tread (every step)", g["tread"], "m", tol.get("tread")),
                 ("foothold 0 from the back of tread 0", g["landing_offset"], "m", None),
                 ("foothold advance per step (horizontal)", g["advance"], "m", None)]
    else:
        rows += [("slope", g["slope"], "rad", tol.get("slope")),
                 ("foothold spacing along the ramp (2 l sin(pi/n))", g["chord"], "m", None)]
    rows += [("spokes", g["n"], "", None),
             ("spoke length (hub centre to tip)", g["leg"], "m", None),
             ("angle between spokes", 2 * g["alpha"], "rad", None),
             ("spoke mass (each)", w.spoke_mass, "kg", None),
             ("hub mass", w.mass, "kg", None),
             ("hub radius of gyration", w.gyration, "m", None),
             ("tip friction (Coulomb, at least)", spec.scene.friction, "", None),
             ("start speed (after the first impact)", spec.scene.initial.speed, "rad/s",
              spec.scene.initial.speed_tolerance or None),
             ("speed after each impact (periodic)", analysis.periodic.get("post_impact_speed"),
              "rad/s", None)]
    return rows


def box_tolerances(sheet, why: str) -> tuple[ToleranceEntry, ...]:
    """The box's half-widths on the steps they cover: the ramp's slope (rad), or every
    step's rise and tread (m)."""
    covers = f"steps 1 to {sheet.tolerance_covers}"
    where = covers if sheet.spec.scene.ground == "stairs" else f"the ramp's slope, {covers}"
    units = {"slope": "rad", "rise": "m", "tread": "m"}
    return tuple(ToleranceEntry(f"{axis} (box)", where, value, units.get(axis, "m"), why)
                 for axis, value in sheet.tolerance.items())


def parts(sheet) -> list[Part]:
    spec = sheet.spec
    g, w = numbers(spec), spec.scene.wheel
    pitch = math.degrees(2 * g["alpha"])
    out = [Part("hub", 1, f"mass {w.mass * 1e3:.4g} g, radius of gyration about its centre "
                          f"{mm(w.gyration)} mm (the spokes' centre)"),
           Part("spoke", g["n"], f"length {mm(g['leg'])} mm from the hub's centre to the tip, "
                                 f"mass {w.spoke_mass * 1e3:.4g} g (a uniform rod), "
                                 f"{pitch:.4g} deg apart (spoke j at j x {pitch:.4g} deg)"),
           Part("spoke tip", g["n"], f"friction coefficient on the ground at least "
                                     f"{spec.scene.friction:g}")]
    if g["stairs"]:
        out.append(Part("step", sheet.count,
                        f"rise {mm(g['rise'])} mm, tread {mm(g['tread'])} mm; foothold 0 "
                        f"{mm(g['landing_offset'])} mm from the back of tread 0"))
    else:
        out.append(Part("ramp", 1, f"slope {deg(g['slope'])} deg, at least "
                                   f"{mm((sheet.count + 1) * g['chord'])} mm long; footholds "
                                   f"{mm(g['chord'])} mm apart along it"))
    return out


def table_rows(sheet) -> list[str]:
    """Fixed-width rows of the footholds (and, on stairs, the steps), mm and degrees."""
    if sheet.spec.scene.ground == "stairs":
        rows = [f"{'k':>4} {'rise':>10} {'tread':>10} {'back x':>12} {'nose x':>12} "
                f"{'level':>12} {'foot x':>12} {'tol rise':>9} {'tol tread':>9}"]
        for i in sheet.items:
            rows.append(f"{i['step']:>4} {i['rise_m'] * MM:>10.3f} {i['tread_m'] * MM:>10.3f} "
                        f"{i['back_x_m'] * MM:>12.3f} {i['nose_x_m'] * MM:>12.3f} "
                        f"{i['level_m'] * MM:>12.3f} {i['foot_x_m'] * MM:>12.3f} "
                        f"{_tol(i['rise_tolerance_m'], MM):>9} "
                        f"{_tol(i['tread_tolerance_m'], MM):>9}")
        return rows
    rows = [f"{'k':>4} {'slope deg':>10} {'along':>12} {'foot x':>12} {'foot y':>12} "
            f"{'tol deg':>9}"]
    for i in sheet.items:
        rows.append(f"{i['step']:>4} {math.degrees(i['slope_rad']):>10.4f} "
                    f"{i['along_ramp_m'] * MM:>12.3f} {i['foot_x_m'] * MM:>12.3f} "
                    f"{i['foot_y_m'] * MM:>12.3f} "
                    f"{_tol(i['slope_tolerance_rad'], 180 / math.pi):>9}")
    return rows


def _tol(value, scale) -> str:
    return "-" if value is None or not math.isfinite(value) else f"+-{value * scale:.3g}"


def wheel_spokes(spec, g: dict | None = None):
    """The wheel at its start, mm: (hub, [tip of spoke j]) with spoke 0 on foothold 0 at
    beta - alpha from the vertical (behind the hub's vertical on a downhill chord)."""
    g = g or numbers(spec)
    phi = g["beta"] - g["alpha"]
    leg = g["leg"] * MM
    hub = (leg * math.sin(phi), leg * math.cos(phi))
    tips = [(hub[0] - leg * math.sin(phi - 2 * g["alpha"] * j),
             hub[1] - leg * math.cos(phi - 2 * g["alpha"] * j)) for j in range(g["n"])]
    return hub, tips
