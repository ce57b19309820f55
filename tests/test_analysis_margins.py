"""The analysis' margins of the paper's manipulators (problems/paper_manipulators.toml), each
computed here by hand from the paper's numbers and the definitions of docs/physics.md (section 2,
and section 4: margin = (capacity - demand) / max(capacity, demand), 1 - demand/capacity while
the condition holds). Plain math, no pdm_design formula: the first landing is the ballistic flight
onto palm 1 at rest at -alpha, the landing impulse the plastic sticking one, the handover the
periodic fixed point, the contact force's point on the base (h/2) tan(theta) from the centre.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from pdm_design.analysis import analyse
from pdm_design.spec import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"

# the paper's example 3 and our sizes (paper_manipulators.toml)
G, L, ALPHA, BETA = 9.81, 2.0, 0.2, 0.6
m, M, MU = 1.0, 0.1, 0.8
X0, Y0, VX0, VY0 = -1.25, 3.05, 3.0, 0.0
w, h, W = 0.4, 0.2, 1.6  # object width and height, palm width
K = m / (m + M)


def margin(capacity, demand):
    return (capacity - demand) / max(capacity, demand)


# palm 1 (pivot at the origin) at rest at -alpha: its top surface's centre
PALM_X, PALM_Y = -L * math.sin(ALPHA), L * math.cos(ALPHA)
# ballistic flight down to that surface
T_FALL = math.sqrt(2 * (Y0 - PALM_Y) / G)  # VY0 = 0
OFFSET = X0 + VX0 * T_FALL - PALM_X  # object's centre ahead of the palm's centre
FIRST_V = (VX0, VY0 - G * T_FALL)
# the periodic handover: s*^2 = 2 g l (cos a - cos b) / (1 - K^2 cos^2(a + b)), along t(beta)
S2 = 2 * G * L * (math.cos(ALPHA) - math.cos(BETA)) / (1 - K**2 * math.cos(ALPHA + BETA) ** 2)
PERIODIC_V = (math.sqrt(S2) * math.cos(BETA), -math.sqrt(S2) * math.sin(BETA))
# the supported part of the base (relative to its centre): all of it when it lands this far in
SUPPORT = (max(-w / 2, -W / 2 - OFFSET), min(w / 2, W / 2 - OFFSET))


STAGES = [("first_", FIRST_V), ("", PERIODIC_V)]  # the first approach's margins, the orbit's


def landing(v):
    """(u, px, py): speed of object + palm along t(-alpha) = (cos a, sin a) after the plastic
    landing (momentum m V . t shared with the palm, the links taking the radial part), and the
    impulse per unit mass on the object, m u t - m V."""
    u = K * (v[0] * math.cos(ALPHA) + v[1] * math.sin(ALPHA))
    return u, u * math.cos(ALPHA) - v[0], u * math.sin(ALPHA) - v[1]


def tip(point):
    """Margin of a force crossing the base at `point` (ahead +) within the supported part."""
    return margin(SUPPORT[1], point) if point >= 0 else margin(-SUPPORT[0], -point)


@pytest.fixture(scope="module")
def margins():
    spec = load_spec(PROBLEMS / "paper_manipulators.toml")
    return analyse(spec.scene, spec.design_at(), spec.verification.stages).margins


def test_the_hand_numbers_are_the_papers_scene():
    # docs/physics.md section 4: the object lands 0.561 m ahead of the first palm's centre
    assert OFFSET == pytest.approx(0.561, abs=5e-4)
    assert SUPPORT == (-w / 2, w / 2)  # the whole base rests on the palm
    assert math.sqrt(S2) == pytest.approx(3.184, abs=5e-4)  # docs: s* = 3.184 m/s


def test_landing_margin(margins):
    # half the palm against the object's far edge: 1 - (0.5615 + 0.2) / 0.8 = 0.048
    expected = margin(W / 2, abs(OFFSET) + w / 2)
    assert expected == pytest.approx(0.048, abs=1e-3)
    assert margins["landing"] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("prefix, v", STAGES, ids=["first", "periodic"])
def test_slip_at_the_landing_impact(margins, prefix, v):
    # sticks iff |px| <= mu py: the capacity is mu py, the demand |px|
    _, px, py = landing(v)
    assert py > 0
    assert margins[f"{prefix}slip_impact"] == pytest.approx(margin(MU * py, abs(px)), rel=1e-9)


@pytest.mark.parametrize("prefix, v", STAGES, ids=["first", "periodic"])
def test_tip_at_the_landing_impact(margins, prefix, v):
    # the impulse passes through the centre of mass, h/2 above the base: it crosses the base
    # (h/2) |px| / py from the centre, on the side opposite to px
    _, px, py = landing(v)
    assert margins[f"{prefix}tip_impact"] == pytest.approx(tip(-(h / 2) * px / py), rel=1e-9)


def test_tip_during_the_carry(margins):
    # the contact force crosses the base (h/2) tan(theta) behind the centre: ahead at -alpha,
    # behind at beta; the larger |theta| (beta) binds
    at_stop = tip((h / 2) * math.tan(ALPHA))
    at_handover = tip(-(h / 2) * math.tan(BETA))
    assert at_handover < at_stop
    assert margins["tip_carry"] == pytest.approx(min(at_stop, at_handover), rel=1e-9)
    assert margins["tip_carry"] == pytest.approx(1 - (h / 2) * math.tan(BETA) / (w / 2),
                                                 rel=1e-9)


def test_slip_during_the_carry(margins):
    # friction / normal = |tan theta|, largest at beta
    assert margins["slip_carry"] == pytest.approx(margin(MU, math.tan(BETA)), rel=1e-9)


@pytest.mark.parametrize("prefix, v", STAGES, ids=["first", "periodic"])
def test_over_the_top_and_lift_off(margins, prefix, v):
    u, _, _ = landing(v)
    # over the top iff u^2 > 2 g l (1 - cos alpha)
    assert margins[f"{prefix}over_the_top"] == pytest.approx(
        margin(u**2, 2 * G * L * (1 - math.cos(ALPHA))), rel=1e-9)
    # lift-off at v^2 >= g l cos(theta), checked at both ends of the carry
    v_beta2 = u**2 + 2 * G * L * (math.cos(ALPHA) - math.cos(BETA))
    expected = min(margin(G * L * math.cos(ALPHA), u**2),
                   margin(G * L * math.cos(BETA), v_beta2))
    assert margins[f"{prefix}lift_off"] == pytest.approx(expected, rel=1e-9)
    if prefix == "":  # docs/physics.md section 3: the correct speed leaves a lift-off margin 0.37
        assert margins["lift_off"] == pytest.approx(0.37, abs=5e-3)


def test_a_row_of_one_judges_only_palm_1():
    # One manipulator: the object lands on palm 1 and is carried to beta; no landing follows.
    # The periodic orbit's landing margins (over the top, lift-off at the landing, slip and tip
    # at the impact) belong to palms 2..; palm 1's are the first_ ones, the carry's are shared.
    spec = load_spec(PROBLEMS / "paper_manipulators.toml")
    one = analyse(spec.scene, spec.design_at(), 1).margins
    row = analyse(spec.scene, spec.design_at(), 6).margins
    later = {"over_the_top", "lift_off", "slip_impact", "tip_impact"}
    assert later <= set(row) and not later & set(one)
    assert {k: v for k, v in row.items() if k not in later | {"parked_palms"}} == one
