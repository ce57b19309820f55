"""Conditions in a designer's words (used by the elastic diagnosis)."""

from __future__ import annotations

import re

CONDITIONS = {
    # manipulators
    "over_the_top": ("the object is carried over the top of the palm's arc",
                     "raise the landing speed: larger beta - alpha, smaller alpha, lighter palm"),
    "first_over_the_top": ("the first landing carries the object over the top",
                           "move the first manipulator or reduce alpha"),
    "lift_off": ("the object stays pressed on the palm (no lift-off)",
                 "slow the carry: smaller beta - alpha or longer links"),
    "first_lift_off": ("the object stays on palm 1 after the first landing",
                       "lower the start or move the first manipulator"),
    "slip_carry": ("friction holds the object on the palm during the carry",
                   "smaller alpha and beta, or more friction"),
    "tip_carry": ("the object does not tip over during the carry",
                  "smaller angles, a wider or lower object, or centre the landing"),
    "slip_impact": ("the object sticks where it lands on a palm",
                    "land more along the palm's path: change alpha + beta or the mass ratio"),
    "first_slip_impact": ("the object sticks where it first lands",
                          "change the start velocity, alpha or the mass ratio"),
    "tip_impact": ("the object does not tip when it lands on a palm",
                   "a wider or lower object, or centre the landing"),
    "first_tip_impact": ("the object does not tip when it first lands",
                         "centre the first landing on palm 1"),
    "landing": ("the object lands fully on the palm",
                "move the first manipulator to centre the landing, or widen the palm"),
    "palm_clearance": ("the next palm stays below the object until the handover",
                       "larger beta - alpha (more drop per stage) or a smaller offset box"),
    "front_stop": ("the palm hands over before its front stop", "smaller beta or a later stop"),
    "parked_palms": ("the carried object clears the palms parked at their front stops behind it",
                     "a later front stop, narrower palms, or a longer pitch (larger alpha + beta)"),
    "forward_landing": ("the landing pushes the palm forward", "smaller alpha + beta"),
    "start_height": ("the object starts above palm 1's top surface (at first_pivot_y + "
                     "link_length cos alpha)",
                     "raise the start (initial.position) or lower the first pivot "
                     "(first_pivot_y); a larger alpha or a shorter link lowers palm 1 too"),
    # stairs
    "riser_clearance": ("the ball lands clear of the riser behind it",
                        "land further forward on the tread (a larger landing_offset)"),
    "nose_clearance": ("the ball clears the nose of the step it leaves",
                       "move the landing along the tread (landing_offset)"),
    "first_nose_clearance": ("the launch clears the top landing's nose",
                             "land further forward on tread 1 (a larger landing_offset moves the "
                             "stairs back under the launch), or a slower launch"),
    "first_impact_friction": ("friction stops the ball slipping at the first impact",
                              "more friction, or launch speed and spin that match rolling"),
    "periodic_tread": ("the tread matches the periodic flight (no drift per bounce)",
                       "free the tread or the launch speed"),
    "forward_flight": ("the ball keeps moving down the stairs", "a faster launch"),
    "step_down": ("every step goes down", "a larger rise"),
}


def flat_floor(spec, design: dict) -> str | None:
    """Why a staircase sized for a tolerance box cannot be built at restitution 1 (None
    otherwise): its periodic rise (1 - eps^2) h0 is 0, a flat floor, and a rise error of any
    size makes a step go up (the step_down row holds the box below the rise)."""
    if (spec.kind != "stairs" or not float(design.get("restitution") or 0.0) >= 1.0
            or not float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0):
        return None
    return ("restitution 1 gives a periodic rise (1 - restitution^2) h0 = 0: the steps are a "
            "flat floor, where a rise error of any size makes a step go up, so no tolerance box "
            "exists (objective max_offset_tolerance): give a restitution below 1, or drop that "
            "objective")


# The way to move a nose_clearance row's landing depends on the phase of the flight its `where`
# names (formulation/stairs/__init__.py NOSE_ENDS): landing_offset is measured from the back of the
# tread, so a smaller one takes off further behind the nose ahead, a larger one nearer to it.
_BACK = "land further back on the tread (a smaller landing_offset)"
_FORWARD = "land further forward on the tread (a larger landing_offset)"
PHASE_HINTS = {
    "nose_clearance": (
        ("takes off", f"{_BACK}: it lands too near the nose ahead"),
        ("comes down", f"{_FORWARD}: it comes down on the nose ahead"),
    ),
}


def hint(name: str, where: str) -> str:
    """What to change, in words, for condition `name` violated at `where`."""
    for phrase, text in PHASE_HINTS.get(name, ()):
        if phrase in where:
            return text
    return CONDITIONS.get(name, ("", ""))[1]


def normalised_margin(slack: float, scale: float) -> float:
    """The analysis' margin (c - d) / max(c, d) from slack = c - d and scale = c."""
    slack, scale = float(slack), float(scale)
    if scale <= 0.0:
        return slack if scale == 0.0 else -1.0
    return slack / max(scale, scale - slack)


def describe(name: str, where: str, required: float, achieved: float, *,
             equality: bool = False, value: float | None = None) -> str:
    what = CONDITIONS.get(name, (name.replace("_", " "), ""))[0]
    advice = hint(name, where)
    place = f" ({where})" if where else ""
    if equality:
        text = f"{what}{place}: cannot be met, best achievable residual {value:.3g}"
    else:
        text = (f"{what}{place}: needs margin {required:.3g}, reaches "
                f"{_reached(required, achieved)} at the least-violation design")
    return f"{text}; try: {advice}" if advice else text


def _reached(required: float, achieved: float) -> str:
    """The margin reached, with its shortfall where 3 digits would print the requirement."""
    if f"{achieved:.3g}" != f"{required:.3g}":
        return f"{achieved:.3g}"
    return f"{required:.3g} less {required - achieved:.2g}"


# A row repeated along the device: the same condition at flight (landing) 1, 2, ... or palm 2, ...
_NUMBERED = re.compile(r"\b(flight|landing|palm) (\d+)\b")


def summarise(violations) -> list[str]:
    """The elastic diagnosis' violations (most violated first) in words, one line per condition
    and place: a row violated at several flights or palms is one line that names them all, with
    the worst margin among them."""
    groups: dict[tuple, list] = {}
    for v in violations:
        pattern = _NUMBERED.sub(lambda m: f"{m.group(1)} #", v.where)
        key = (v.name, v.text if v.equality else pattern)
        groups.setdefault(key, []).append(v)
    lines = []
    for (name, pattern), members in groups.items():
        if len(members) == 1:
            if members[0].text not in lines:  # a row held by two keys is one line
                lines.append(members[0].text)
            continue
        kind = _NUMBERED.search(members[0].where).group(1)
        numbers = sorted({int(_NUMBERED.search(v.where).group(2)) for v in members})
        where = pattern.replace(f"{kind} #", f"{kind}s {_spans(numbers)}", 1)
        worst = min(members, key=lambda v: v.achieved - v.required)
        lines.append(describe(name, where, worst.required, worst.achieved))
    return lines


def _spans(numbers: list[int]) -> str:
    """[1, 2, 3, 5] -> '1-3, 5'."""
    spans: list[list[int]] = []
    for n in numbers:
        if spans and n == spans[-1][1] + 1:
            spans[-1][1] = n
        else:
            spans.append([n, n])
    return ", ".join(f"{a}" if a == b else f"{a}-{b}" for a, b in spans)


def bounds_hint(at_bounds) -> str:
    """The design variables at a bound of the least-violation design, as advice ("" if none)."""
    if not at_bounds:
        return ""
    return (f"at the least-violation design {', '.join(at_bounds)}: widening "
            f"{'that bound' if len(at_bounds) == 1 else 'those bounds'} may help")
