"""A staircase's conditions in a designer's words: {name: (what it asks, what to change)}, and
the advice that depends on the phase of the flight a row guards (Scene.condition_words;
solve/words.py)."""

CONDITIONS = {
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

# The way to move a nose_clearance row's landing depends on the phase of the flight its `where`
# names (formulation/__init__.py NOSE_ENDS): landing_offset is measured from the back of the
# tread, so a smaller one takes off further behind the nose ahead, a larger one nearer to it.
_BACK = "land further back on the tread (a smaller landing_offset)"
_FORWARD = "land further forward on the tread (a larger landing_offset)"
PHASE_HINTS = {
    "nose_clearance": (
        ("takes off", f"{_BACK}: it lands too near the nose ahead"),
        ("comes down", f"{_FORWARD}: it comes down on the nose ahead"),
    ),
}


def flat_floor(spec, design: dict) -> str | None:
    """Why a staircase sized for a tolerance box cannot be built at restitution 1 (None
    otherwise): its periodic rise (1 - eps^2) h0 is 0, a flat floor, and a rise error of any
    size makes a step go up (the step_down row holds the box below the rise)."""
    if (not float(design.get("restitution") or 0.0) >= 1.0
            or not float(spec.objective.get("max_offset_tolerance", 0.0)) > 0.0):
        return None
    return ("restitution 1 gives a periodic rise (1 - restitution^2) h0 = 0: the steps are a "
            "flat floor, where a rise error of any size makes a step go up, so no tolerance box "
            "exists (objective max_offset_tolerance): give a restitution below 1, or drop that "
            "objective")
