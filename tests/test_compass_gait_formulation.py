"""The compass gait's NLP (formulation.build through the shared assembly and IPOPT) against the
standalone step map: the most stable walker of the template (leg_com free) against a scan of
fixed_point's spectral radius, and the NLP's gait against fixed_point's at its optimum."""

import tomllib
from types import SimpleNamespace

import numpy as np
import pytest

from pdm_design.formulation.common import assemble
from pdm_design.scenes.compass_gait.formulation import build, shared_objective
from pdm_design.scenes.compass_gait.gait import fixed_point
from pdm_design.scenes.compass_gait.spec import design_at, read_tables
from pdm_design.scenes.compass_gait.template import compass_gait_template

ca = pytest.importorskip("casadi")


def spec_of(text, **design):
    data = tomllib.loads(text)
    scene, values = read_tables(data, "template")
    values.update(design)
    return SimpleNamespace(scene=scene, design=values, kind="compass_gait",
                           objective=shared_objective(data.get("objective", {})),
                           requirements=data.get("requirements", {}),
                           verification=SimpleNamespace(stages=50))


def solve(spec, start):
    model, bounds, _ = build(spec)
    form = assemble(spec, model, key="compass_gait", bounds=bounds)
    solver = ca.nlpsol("s", "ipopt", form.nlp, {"ipopt.print_level": 0, "print_time": 0})
    sol = solver(x0=form.start_vector(start), p=form.parameters(), lbx=form.lbx, ubx=form.ubx,
                 lbg=form.lbg, ubg=form.ubg)
    assert solver.stats()["success"]
    return dict(zip(form.x_names, np.asarray(sol["x"]).ravel()))


def radius_at(spec, leg_com):
    values = dict(spec.design)
    values["leg_com"] = leg_com
    return fixed_point(spec.scene, design_at(values))["spectral_radius"]


def test_most_stable_leg_com_matches_a_scan_of_the_step_map():
    from pdm_design.spec.model import Bounds

    # a range whose optimum is inside (the radius is smallest near 0.2 m from the hip, where
    # the complex pair and the real multiplier are equal: a kink Jury's rows handle)
    spec = spec_of(compass_gait_template())
    spec.design["leg_com"] = Bounds(min=0.15, max=0.45, initial=0.4)
    x = solve(spec, {"leg_com": 0.4})
    grid = np.linspace(0.15, 0.45, 31)
    radii = [radius_at(spec, c) for c in grid]
    best = int(np.argmin(radii))
    # the NLP's optimum is no worse than the scan's best and lies next to it
    assert radius_at(spec, x["leg_com"]) <= radii[best] + 1e-6
    assert abs(x["leg_com"] - grid[best]) <= 0.01 + 1e-9
    # the bound rho is the spectral radius there (Jury's rows are exact)
    assert x["spectral_radius_bound"] == pytest.approx(radius_at(spec, x["leg_com"]), abs=1e-5)


def test_the_nlp_gait_is_fixed_points():
    spec = spec_of(compass_gait_template())
    x = solve(spec, {"leg_com": 0.5})
    values = dict(spec.design)
    values["leg_com"] = x["leg_com"]
    point = fixed_point(spec.scene, design_at(values))["fixed_point"]
    for name in ("stance", "swing", "stance_rate", "swing_rate"):
        assert x[name] == pytest.approx(point[name], abs=1e-6)
