"""A run whose events come without end ends, named: the long row at twice a yield target's
pivot tolerances, build 353 (seed 0), rocks on palm 50 and is caught again and again, 7e-9 s
apart. Before the chattering guard it ran to the event budget (202,000 events, minutes of a
yield run); now it ends `too_many_events` once 50 events fall within 1e-6 s."""

from dataclasses import replace
from pathlib import Path

from pdm_design.plugin import of
from pdm_design.scenes.manipulators.sim.run import CHATTER_EVENTS, CHATTER_SPAN
from pdm_design.spec import load_spec
from pdm_design.tolerances.yield_ import one_build

LONG_ROW = Path(__file__).resolve().parents[1] / "problems" / "manipulators_long_row.toml"
PIVOTS = 0.19499756063237356 / 2.0  # the 99 % target's allocation (test_max_yield)


def test_catches_without_end_stop_the_run_as_chattering():
    spec = load_spec(LONG_ROW)
    tolerances = replace(spec.tolerances, items=tuple(
        replace(t, value=PIVOTS) if t.quantity in ("pivot_x", "pivot_y") else t
        for t in spec.tolerances)).scaled(2.0)
    deviations = one_build(tolerances, 0, 353, 100, scene=spec.scene)
    result = of(spec.scene).simulate_build(spec.scene, spec.design_at(), deviations, 100)
    outcome, events = result.outcome, result.events
    assert not outcome.completed and outcome.failure.kind == "too_many_events"
    assert "chattering" in outcome.failure.detail
    last = events[-CHATTER_EVENTS - 1:-1]  # the failure's own event after them
    assert last[-1].time - last[0].time < CHATTER_SPAN
    assert sum(e.kind == "catch" for e in last) >= CHATTER_EVENTS // 3
    assert len(events) < 2000  # not the budget's 202,000
