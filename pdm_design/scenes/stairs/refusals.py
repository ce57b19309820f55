"""What a staircase's tolerances cannot be: the quantities a yield cannot draw builds of."""

from __future__ import annotations

from ...tolerance_model import zero_nominal


def tolerance_refusal(spec, quantity: str) -> tuple[str, str, str] | None:
    """(key, expected, found) refusing a friction tolerance of a point ball (it cannot roll)
    or of a frictionless material; None otherwise."""
    if quantity != "friction":
        return None
    if spec.scene.ball.radius == 0:
        return ("tolerances.friction", "no friction tolerance for a point ball (a ball of "
                "radius 0 cannot roll: give scene.ball a radius)", "scene.ball.radius = 0")
    return zero_nominal(quantity, spec.scene.friction, "a scene.friction")
