"""A row of manipulators' conditions in a designer's words: {name: (what it asks, what to
change)} (Scene.condition_words; solve/words.py)."""

CONDITIONS = {
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
}
