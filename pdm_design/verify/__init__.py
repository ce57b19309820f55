"""Verification: simulate a design from the spec's initial state and judge the closed forms.

The simulator is the judge. A design passes when the run completes every requested stage and,
for a nominally built device, the simulated periodic quantities agree with the closed forms to
the tolerance the accuracy preset promises.
"""

from __future__ import annotations

from ..accuracy import accuracy as accuracy_preset
from ..analysis import Analysis
from ..plugin import of
from ..sim.core import SimulationRefused
from ..spec.model import Spec
from ..units import counted


def simulate_spec(spec: Spec, design, *, stages=None, errors=None, accuracy=None,
                  record_trajectory=False):
    """Run the event simulator on `design` with the spec's (or the given) settings. errors:
    the per-stage build errors the scene takes (Scene.stage_errors; None: the spec's own)."""
    verification = spec.verification
    stages = verification.stages if stages is None else stages
    accuracy = accuracy_preset(accuracy or verification.accuracy)
    return of(spec).simulate(spec, design, stages=stages, accuracy=accuracy, errors=errors,
                             record_trajectory=record_trajectory)


def verify_nominal(spec: Spec, design, analysis: Analysis, *, accuracy=None) -> dict:
    """Simulate the design as built (with the spec's own offsets or step errors, if any) and
    compare with the closed forms when it is built exactly."""
    acc = accuracy_preset(accuracy or spec.verification.accuracy)
    try:
        result = simulate_spec(spec, design, accuracy=acc)
    except SimulationRefused as refusal:
        return {
            "passed": False,
            "summary": f"the simulator refuses this design: {refusal}",
            "accuracy": acc.name,
            "accuracy_settings": acc.settings(),
            "outcome": {"completed": False, "stages_passed": 0,
                        "failure": {"event": "refused", "stage": 0, "time": 0.0,
                                    "detail": str(refusal)}},
            "agreement": None,
            "samples": 0,
            "failures": [f"the simulator refuses this design: {refusal}"],
        }
    outcome = result.outcome
    failures = []
    if not outcome.completed:
        where = outcome.failure
        what = f"{where.kind} at stage {where.stage}: {where.detail}" if where else "incomplete"
        failures.append(f"nominal run stopped after {counted(outcome.stages_passed, 'stage')} "
                        f"({what})")
    exact_build = not spec.verification.has_stage_items
    # a run that left the closed forms' regime (an object that lifted off and flew) is judged
    # by its outcome: the closed forms describe neither that nor the stages after it
    left = of(spec).left_closed_forms(result)
    agreement = (of(spec).closed_form_agreement(spec, analysis, result)
                 if exact_build and not left else None)
    if agreement is not None and not agreement["relative_error"] <= acc.agreement:
        failures.append(f"simulator and closed form disagree on {agreement['quantity']}: "
                        f"relative error {agreement['relative_error']:.2e}"
                        f"{of(spec).disagreement_note(spec)}")
    summary = (f"{counted(outcome.stages_passed, 'stage')} simulated from the initial state"
               + (", closed forms confirmed" if agreement and not failures else "")
               + left)
    return {
        "passed": not failures,
        "summary": summary if not failures else "; ".join(failures),
        "accuracy": acc.name,
        "accuracy_settings": acc.settings(),
        "outcome": outcome.to_json(),
        "agreement": agreement,
        "samples": 1,
        "failures": failures,
    }
