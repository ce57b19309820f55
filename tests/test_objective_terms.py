"""`objective.terms` of `pdm-design optimize --format json`: each objective's value at the design.

Expected values come from the closed-form analysis run here on the reported design
(`analysis.analyse`, not the optimizer's rows or the report's code) and from the definitions in
docs/spec.md section 6, written out by hand.
"""

import json
import math
from pathlib import Path

import pytest
from click.testing import CliRunner

from pdm_design.analysis import analyse
from pdm_design.cli import main
from pdm_design.spec import load_spec

PROBLEMS = Path(__file__).resolve().parents[1] / "problems"


def optimize_json(path):
    result = CliRunner().invoke(main, ["optimize", str(path), "--format", "json"])
    return result.exit_code, json.loads(result.stdout)


def _variant(tmp_path, problem, objective, requirements=None):
    """A shipped problem (asking for max_offset_tolerance only) with that objective replaced
    and, if given, a [requirements] table (for a problem that has none)."""
    text = (PROBLEMS / problem).read_text()
    asked = "[objective]\nmax_offset_tolerance = 1.0\n"
    assert asked in text
    table = "[objective]\n" + "".join(f"{k} = {v}\n" for k, v in objective.items())
    if requirements:
        assert "[requirements]" not in text
        table += "\n[requirements]\n" + "".join(f"{k} = {v}\n" for k, v in requirements.items())
    path = tmp_path / "variant.toml"
    path.write_text(text.replace(asked, table))
    return path


def _analysed_margins(path, doc):
    """The margins of the reported design by the closed-form analysis, run here."""
    spec = load_spec(path)
    free = {n: doc["design"][n] for n in spec.free_variables}
    return analyse(spec.scene, spec.design_at(free), spec.verification.stages).margins


def test_stairs_max_min_margin_counts_the_exact_nose_clearance(tmp_path):
    """The optimizer once maximised 0.665 (the riser clearance) while the nose clearance was
    0.166. What it maximises must be the smallest reported margin (each less
    its requirement: riser_clearance 0.02), the nose's exact gap included."""
    path = _variant(tmp_path, "stairs_design.toml", {"max_min_margin": 1})
    code, doc = optimize_json(path)
    assert code == 0 and doc["status"] == "optimal"
    margins = _analysed_margins(path, doc)
    assert set(margins) == {"first_nose_clearance", "nose_clearance", "riser_clearance"}
    smallest = min(v - (0.02 if k == "riser_clearance" else 0.0) for k, v in margins.items())
    # the NLP's epigraph (the score it reached) is that smallest margin, to its backoff 1e-6
    assert doc["objective"]["value"] == pytest.approx(smallest, abs=1e-5)
    assert doc["objective"]["terms"]["max_min_margin"] == pytest.approx(smallest, abs=1e-12)
    # and the nose is what limits it: the old answer's riser-driven 0.65 is far above it
    assert smallest < 0.5


def test_max_min_margin_is_each_margin_less_its_requirement(tmp_path):
    """Manipulators with requirements on landing and tip_carry (one row each): the term is
    min(margin - requirement) over every margin but parked_palms."""
    reqs = {"landing": 0.1, "tip_carry": 0.3}
    path = _variant(tmp_path, "manipulators_robust.toml", {"max_min_margin": 1.0}, reqs)
    code, doc = optimize_json(path)
    assert code == 0 and doc["status"] == "optimal"
    assert doc["requirements"] == reqs
    margins = _analysed_margins(path, doc)
    expected = min(v - reqs.get(k, 0.0) for k, v in margins.items() if k != "parked_palms")
    assert doc["objective"]["terms"]["max_min_margin"] == pytest.approx(expected, abs=1e-12)
    assert doc["objective"]["value"] == pytest.approx(expected, abs=1e-5)
    # the plain smallest margin is larger: the requirement is subtracted
    assert min(v for k, v in margins.items() if k != "parked_palms") > expected


def test_a_shared_row_holds_both_margins_to_the_larger_requirement(tmp_path):
    """lift_off and first_lift_off are held by one NLP row (docs/spec.md section 6): a
    requirement on either holds both, and the term subtracts the larger from each."""
    reqs = {"lift_off": 0.75}
    path = _variant(tmp_path, "manipulators_robust.toml", {"max_min_margin": 1.0}, reqs)
    code, doc = optimize_json(path)
    assert code == 0
    margins = _analysed_margins(path, doc)
    need = {k: 0.75 if k in ("lift_off", "first_lift_off") else 0.0 for k in margins}
    expected = min(v - need[k] for k, v in margins.items() if k != "parked_palms")
    assert doc["objective"]["terms"]["max_min_margin"] == pytest.approx(expected, abs=1e-12)
    assert doc["objective"]["value"] == pytest.approx(expected, abs=1e-5)
    # first_lift_off, held to lift_off's requirement, is one of the margins that bind
    assert margins["first_lift_off"] - 0.75 == pytest.approx(expected, abs=1e-5)


def test_unweighted_terms_are_their_values_at_the_design():
    """manipulators_robust asks only for the tolerance: the other terms are still reported, at
    the design (max_min_margin was once reported as 0.0 where the smallest margin was 0.329)."""
    code, doc = optimize_json(PROBLEMS / "manipulators_robust.toml")
    assert code == 0
    terms, design = doc["objective"]["terms"], doc["design"]
    margins = {k: v for k, v in doc["margins"].items() if k != "parked_palms"}
    assert terms["max_min_margin"] == pytest.approx(min(margins.values()), abs=1e-12)
    assert terms["max_min_margin"] > 0.3
    a, b, l, q = design["alpha"], design["beta"], design["link_length"], design["mass_ratio"]
    assert terms["min_drop"] == pytest.approx(l * (math.cos(a) - math.cos(b)), rel=1e-9)
    assert terms["fastest_convergence"] == pytest.approx((q / (q + 1) * math.cos(a + b)) ** 2,
                                                         rel=1e-9)
    assert terms["max_offset_tolerance"] == pytest.approx(doc["tolerance"]["dx"], rel=1e-12)


def test_an_unasked_tolerance_is_null_not_zero(tmp_path):
    path = _variant(tmp_path, "stairs_design.toml", {"max_min_margin": 1})
    _, doc = optimize_json(path)
    assert doc["tolerance"] is None
    assert doc["objective"]["terms"]["max_offset_tolerance"] is None
    eps, rise = doc["design"]["restitution"], doc["design"]["rise"]
    assert doc["objective"]["terms"]["fastest_convergence"] == pytest.approx(eps**2, rel=1e-12)
    assert doc["objective"]["terms"]["min_drop"] == pytest.approx((1 - eps**2) * 1.0, rel=1e-9)
    assert rise == pytest.approx((1 - eps**2) * 1.0, rel=1e-9)


def test_every_row_that_holds_two_margins_holds_each_to_the_others_requirement():
    # The judge of a fixed design (analysis.result.required) and the NLP's rows agree on which
    # requirements hold which margins: a row takes the largest requirement of its keys, so they
    # must all hold the margin it is named after; a manipulators row that measures two margins
    # (SHARED_ROWS) holds each to the other's requirement.
    from pdm_design.formulation import formulate
    from pdm_design.plugin import scene_kind
    from pdm_design.scenes.manipulators.formulation import SHARED_ROWS

    for problem in ("manipulators_robust.toml", "stairs_design.toml"):
        spec = load_spec(PROBLEMS / problem)
        covered = scene_kind(spec.kind).covered_by
        for info in formulate(spec, full=True).conditions:
            assert set(info.keys) - {info.name} <= set(covered.get(info.name, ())), info.label
    covered = scene_kind("manipulators").covered_by
    for a, b in SHARED_ROWS:
        assert b in covered[a] and a in covered[b]


def test_a_first_requirement_holds_a_fixed_designs_periodic_twin(tmp_path):
    # The paper's design with first_lift_off = 0.4: its first landing has 0.4165 to spare, its
    # periodic landings 0.3739. The NLP's one lift-off row holds both to 0.4, so the fixed design
    # is refused too, its periodic margin flagged, as it is with alpha and beta pinned free.
    text = (PROBLEMS / "paper_manipulators.toml").read_text()
    fixed = tmp_path / "fixed.toml"
    fixed.write_text(text + "\n[requirements]\nfirst_lift_off = 0.4\n")
    pinned = tmp_path / "pinned.toml"
    pinned.write_text(fixed.read_text().replace("alpha = 0.2 ", "alpha = { min = 0.2, max = 0.2 } ")
                      .replace("beta = 0.6 ", "beta = { min = 0.6, max = 0.6 } "))
    for path in (fixed, pinned):
        result = CliRunner().invoke(main, ["optimize", str(path)])
        assert result.exit_code == 1, result.stdout
        assert "status: infeasible" in result.stdout
        # a fixed design has no bounds to widen; a pinned free one has
        assert ("widen the bounds" in result.stdout) == (path == pinned)
        (line,) = [x for x in result.stdout.splitlines() if x.startswith("  lift_off ")]
        assert line.endswith("+0.3739  VIOLATED (needs >= 0.4)")
