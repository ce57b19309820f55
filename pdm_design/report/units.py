"""The SI unit of every design, geometry and periodic-orbit quantity, one table for the text
report (report/text.py) and the report page (report/html.py), and which of the links' and
pivots' quantities a device has (massless links and free pivots have none to print)."""

from __future__ import annotations

UNITS = {
    "alpha": "rad", "beta": "rad", "link_length": "m", "mass_ratio": "", "first_pivot_x": "m",
    "first_pivot_y": "m", "restitution": "", "launch_speed": "m/s", "rise": "m", "tread": "m",
    "landing_offset": "m", "pitch_x": "m", "pitch_y": "m", "palm_mass": "kg",
    "nose_clearance": "m", "handover_speed": "m/s", "landing_speed": "m/s", "contraction": "",
    "drop_per_stage": "m", "impact_speed": "m/s", "vertical_impact_speed": "m/s",
    "horizontal_speed": "m/s", "spin": "rad/s", "flight_time": "s", "drift_per_bounce": "m",
    "effective_mass": "kg", "link_mass": "kg", "link_inertia": "kg m^2", "link_count": "",
    "pivot_friction_torque": "N m", "pivot_damping": "N m s/rad",
    "slope": "rad", "leg_length": "m", "spokes": "", "step_length": "m", "step_period": "s",
    "spectral_radius": "",
}

MECHANISM = ("link_mass", "link_inertia", "link_count", "pivot_friction_torque", "pivot_damping")


def built_parts(geometry: dict) -> dict:
    """The geometry to show: the links' and pivots' rows only where the scene has links or
    pivots (massless links and free pivots show none; the JSON keeps every key)."""
    if any(geometry.get(k) for k in MECHANISM if k != "link_count"):
        return geometry
    return {k: v for k, v in geometry.items() if k not in MECHANISM}
