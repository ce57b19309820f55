"""A run whose events come without end ends, named. The long row at twice a yield target's
pivot tolerances, build 353 (seed 0), once rocked on palm 50 and was caught again and again,
7e-9 s apart, to the event budget (202,000 events, minutes of a yield run). Since the object
coming down on a second palm is followed at both contacts (sim/twocontact.py) it comes to rest
across palms 52 and 51 instead; the guard itself is tested on a phase that logs events without
end."""

from dataclasses import replace
from pathlib import Path

from pdm_design.accuracy import accuracy
from pdm_design.plugin import of
from pdm_design.scenes.manipulators.sim.run import CHATTER_EVENTS, CHATTER_SPAN, Run
from pdm_design.spec import load_spec
from pdm_design.tolerances.yield_ import one_build

LONG_ROW = Path(__file__).resolve().parents[1] / "problems" / "manipulators_long_row.toml"
PIVOTS = 0.19499756063237356 / 2.0  # the 99 % target's allocation (test_max_yield)


def test_events_without_end_stop_the_run_as_chattering():
    spec = load_spec(LONG_ROW)
    run = Run(spec.scene, spec.design_at(), 3, (), accuracy("default"), False)
    t = [0.5]

    def catch_again():  # a phase that logs an event 1e-9 s after the last, forever
        t[0] += 1e-9
        run._log(t[0], "catch", 1, {}, {}, "caught again")
        return catch_again

    run._flight = lambda *args, **kwargs: catch_again
    outcome, events = run.run().outcome, run.events
    assert not outcome.completed and outcome.failure.kind == "too_many_events"
    assert "chattering" in outcome.failure.detail
    assert len(events) == CHATTER_EVENTS + 1  # ended at the first 50 within 1e-6 s
    assert events[-2].time - events[0].time < CHATTER_SPAN


def test_the_build_that_chattered_ends_by_name_in_few_events():
    spec = load_spec(LONG_ROW)
    tolerances = replace(spec.tolerances, items=tuple(
        replace(t, value=PIVOTS) if t.quantity in ("pivot_x", "pivot_y") else t
        for t in spec.tolerances)).scaled(2.0)
    deviations = one_build(tolerances, 0, 353, 100, scene=spec.scene)
    result = of(spec.scene).simulate_build(spec.scene, spec.design_at(), deviations, 100)
    assert not result.outcome.completed
    assert result.outcome.failure.kind == "stranded"
    assert len(result.events) < 2000  # not the budget's 202,000
