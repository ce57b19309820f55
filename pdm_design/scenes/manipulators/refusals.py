"""What a row of manipulators' tolerances cannot be: allocations its robust rows do not bound
(docs/optimizer.md section 4a), and quantities a yield cannot draw builds of."""

from __future__ import annotations

from ...tolerance_model import zero_nominal


def allocation_refusal(spec) -> tuple[str, str, str] | None:
    """(key, expected, found) of the first allocation the robust rows cannot bound: the feed
    speed along a sloped start, a link length with the back stops toleranced on real links,
    a link mass or pivot friction of nominal 0; None otherwise."""
    names = {t.quantity for t in spec.tolerances}
    scene = spec.scene
    if scene.initial.velocity[1] != 0.0 and "feed_speed" in names:
        return ("tolerances.feed_speed", "a horizontal start (initial.velocity[1] = 0) to "
                "bound the feed speed's tolerance (along a sloped start it moves the fall "
                "speed as well; not derived yet)",
                f"initial.velocity[1] = {scene.initial.velocity[1]:g}")
    return _links(names, scene) or _mechanism(names, scene)


def _links(names, scene):
    """A link length's tolerance is bounded on the paper's device and on the device as built
    with links and Coulomb pivot friction (the carry's q_e, g_e and f are free of a build's
    link error: docs/optimizer.md section 4a), not with the back stops toleranced too there
    (carry_box.back_contact takes the design's link; damping is refused with every robust
    objective: formulation integrated_steps)."""
    if "link_length" not in names or scene.plain_mechanism or "back_stop" not in names:
        return None
    return ("tolerances.link_length", "the back stops exact to bound the link lengths' "
            "tolerance on real links or pivot friction (the palm's force at a toleranced back "
            "stop is bounded at the design's link only; not derived yet)",
            "tolerances.back_stop with scene.links or scene.pivots")


def _mechanism(names, scene):
    """The built device's quantities: link_mass and pivot_friction need a nominal above 0 (a
    box around 0 is half made of parts below their limit, as `yield` refuses it too)."""
    for name, key, nominal in (("link_mass", "scene.links.mass", scene.links.mass),
                               ("pivot_friction", "scene.pivots.friction_torque",
                                scene.pivots.friction_torque)):
        if name in names and nominal <= 0.0:
            return (f"tolerances.{name}", f"{key} > 0 to bound a tolerance of it (a box "
                    f"around 0 is half made of parts below 0)", f"{key} = {nominal:g}")
    return None


# Quantities whose nominal may be 0, where a +- tolerance around it means nothing (half the
# parts below a physical limit): quantity -> (the nominal, the key that sets it)
_ZERO_NOMINALS = {
    "link_mass": (lambda s: s.links.mass, "a [scene.links] mass"),
    "pivot_friction": (lambda s: s.pivots.friction_torque, "a [scene.pivots] friction_torque"),
    "friction": (lambda s: s.palm.friction, "a scene.palm.friction"),
}


def tolerance_refusal(spec, quantity: str) -> tuple[str, str, str] | None:
    """(key, expected, found) refusing a tolerance around a nominal of 0: links of no mass,
    pivots with no friction, a frictionless palm; None otherwise."""
    found = _ZERO_NOMINALS.get(quantity)
    if found is None:
        return None
    return zero_nominal(quantity, found[0](spec.scene), found[1])
