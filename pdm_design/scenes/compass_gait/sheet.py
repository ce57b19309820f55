"""The compass gait's build sheet (sheet/build.py): the walker's parts (hip mass; each leg's
length, mass, centre of mass from the hip and inertia), the ramp (its slope, the periodic step's
length along it) or the stairs, and one item a step: where its stance foot lands on the periodic
gait. Frame: x downhill along the horizontal, y up, step 1's stance foot at the origin; the
walker stands there at the gait's post-strike state, its trailing foot one step behind."""

from __future__ import annotations

import math
from dataclasses import dataclass

from ...sheet.generic import SheetWords
from ...sheet.parts import MM, Part, ToleranceEntry, deg, mm

PART_WORDS = {"hip": ("hip",), "leg": ("leg",), "ramp": ("ramp", "slope"),
              "stairs": ("stair", "rise", "tread")}
WORDS = SheetWords(item="stance foot",
                   legend="the walker at its post-strike state on the periodic gait (thick: the "
                          "stance leg); dots: where each step's stance foot lands, numbered; "
                          "dotted: the hip's path (simulated)",
                   units="millimetres, degrees")
G_MM2 = 1e9  # kg m^2 -> g mm^2


@dataclass(frozen=True)
class Pose:
    """The walker at the gait's post-strike state, step 1's stance foot at the origin (m): the
    hip, the trailing (swing) foot, the advance (dx, dy) from one stance foot to the next."""

    hip: tuple[float, float]
    trailing: tuple[float, float]
    advance: tuple[float, float]


def pose(fixed_point: dict, leg_length: float) -> Pose:
    """The pose of a fixed point {stance, swing, ...} (rad): the hip at l (sin q1, cos q1), the
    trailing foot at hip - l (sin q2, cos q2); the advance is the swing foot's place at the next
    strike, whose pre-strike angles are the fixed point's swapped (physics.heel_strike)."""
    q1, q2, l = fixed_point["stance"], fixed_point["swing"], leg_length
    hip = (l * math.sin(q1), l * math.cos(q1))
    trailing = (hip[0] - l * math.sin(q2), hip[1] - l * math.cos(q2))
    return Pose(hip, trailing, (l * (math.sin(q2) - math.sin(q1)),
                                l * (math.cos(q2) - math.cos(q1))))


def walker_of(spec):
    return spec.design_at().walker(spec.scene)


def sheet_rows(spec, analysis, tol, count):
    """(summary, items): the walker and the ground (SI), and each step's stance foot."""
    walker, design = walker_of(spec), spec.design_at()
    periodic = analysis.periodic
    fixed = periodic.get("fixed_point")
    if not fixed:
        raise ValueError("the design has no periodic gait to build for: "
                         + "; ".join(analysis.problems))
    advance = pose(fixed, walker.leg_length).advance
    box = (tol or {}).get("slope")
    summary = [("steps", count, "", None)]
    summary.append(("leg length (each leg)", walker.leg_length, "m", None))
    if walker.model == "simplest":
        summary.append(("model", "the simplest walker (point masses: hip >> feet)", "", None))
    else:
        summary += [("hip mass", walker.hip_mass, "kg", None),
                    ("leg mass (each leg)", walker.leg_mass, "kg", None),
                    ("leg centre of mass from the hip", walker.leg_com, "m", None),
                    ("leg inertia about its centre of mass", walker.leg_inertia, "kg m^2",
                     None)]
    if walker.hip_limit is not None:
        summary.append(("hip limit (the legs' largest angle)", walker.hip_limit, "rad", None))
    if design.slope is not None:
        summary.append(("ramp slope", float(design.slope), "rad", box))
    else:
        summary += [("stair rise", float(design.rise), "m", None),
                    ("stair tread", float(design.tread), "m", None)]
    summary += [("step length (periodic, along the ground)", periodic["step_length"], "m",
                 None),
                ("step period (periodic)", periodic["step_period"], "s", None),
                ("spectral radius", periodic["spectral_radius"], "", None)]
    items = [{"step": k, "foot_x_m": (k - 1) * advance[0], "foot_y_m": (k - 1) * advance[1],
              "from_foot_1_m": (k - 1) * periodic["step_length"]}
             for k in range(1, count + 1)]
    return summary, items


def parts(sheet) -> list[Part]:
    spec = sheet.spec
    walker, design = walker_of(spec), spec.design_at()
    if walker.model == "simplest":
        hip = "the walker's mass (the simplest walker: the legs' masses negligible beside it)"
        leg = (f"length {mm(walker.leg_length)} mm, its (negligible) mass at its foot")
    else:
        hip = f"mass {walker.hip_mass * 1e3:.1f} g, at the legs' common pivot"
        leg = (f"length {mm(walker.leg_length)} mm, mass {walker.leg_mass * 1e3:.1f} g, "
               f"centre of mass {mm(walker.leg_com)} mm from the hip")
        if walker.leg_inertia > 0:
            leg += (f", inertia {walker.leg_inertia * G_MM2:.6g} g mm^2 about its centre "
                    "of mass")
    step = mm(sheet.periodic["step_length"])
    if design.slope is not None:
        ground = Part("ramp", 1, f"slope {deg(float(design.slope))} deg; the periodic step "
                      f"{step} mm along it, {sheet.count} steps "
                      f"{mm(sheet.count * sheet.periodic['step_length'])} mm long")
    else:
        advance = pose(sheet.periodic["fixed_point"], walker.leg_length).advance
        ground = Part("stairs", sheet.count, f"rise {mm(float(design.rise))} mm, tread "
                      f"{mm(float(design.tread))} mm; the periodic step {step} mm foot to "
                      f"foot, {mm(advance[0])} mm along the stairs (each foot's place: the "
                      "CSV)")
    return [Part("hip", 1, hip), Part("leg", 2, leg), ground]


def box_tolerances(scene, sheet, why: str) -> tuple:
    """The robust box's slope half-width (rad), on the ramp."""
    if "slope" not in (sheet.tolerance or {}):
        return ()
    return (ToleranceEntry("slope (box)", f"the ramp, steps 1 to {sheet.tolerance_covers}",
                           sheet.tolerance["slope"], "rad", why),)


def table_rows(sheet) -> list[str]:
    """Fixed-width rows of the stance feet, mm."""
    rows = [f"{'step':>4} {'foot x':>12} {'foot y':>12} {'from foot 1':>13}"]
    for item in sheet.items:
        rows.append(f"{item['step']:>4} {item['foot_x_m'] * MM:>12.3f} "
                    f"{item['foot_y_m'] * MM:>12.3f} {item['from_foot_1_m'] * MM:>13.3f}")
    return rows
