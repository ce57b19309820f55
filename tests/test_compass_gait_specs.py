"""The compass-gait spec files, the init template and bad input; the simplest walker's spec
against Garcia et al. (1998)'s published gait at slope 0.009."""

import tomllib
from pathlib import Path

import pytest

from pdm_design.errors import SpecError
from pdm_design.scenes.compass_gait.gait import fixed_point
from pdm_design.scenes.compass_gait.spec import design_at, read_tables
from pdm_design.scenes.compass_gait.template import compass_gait_template

PROBLEMS = Path(__file__).resolve().parent.parent / "problems"


def load(name):
    path = PROBLEMS / name
    return read_tables(tomllib.loads(path.read_text()), str(path))


@pytest.mark.parametrize("name", ["compass_gait_ramp.toml", "simplest_walker.toml",
                                  "compass_gait_robust.toml", "compass_gait_rough.toml"])
def test_problem_files_have_a_stable_gait(name):
    scene, design = load(name)
    gait = fixed_point(scene, design_at(design))
    assert gait["spectral_radius"] < 1.0


def test_the_template_has_a_stable_gait():
    scene, design = read_tables(tomllib.loads(compass_gait_template()), "template")
    assert fixed_point(scene, design_at(design))["spectral_radius"] < 1.0


def test_simplest_walker_is_garcias():
    """Garcia et al. (1998): at slope 0.009 the stable gait has theta = 0.20031 (the stance
    leg from the ramp's normal), theta_dot = -0.19983 and one multiplier exactly 0."""
    scene, design = load("simplest_walker.toml")
    gait = fixed_point(scene, design_at(design))
    point = gait["fixed_point"]
    assert 0.009 - point["stance"] == pytest.approx(0.20031, abs=2e-5)
    assert point["stance_rate"] == pytest.approx(0.19983, abs=2e-5)
    assert min(abs(complex(*m)) for m in gait["multipliers"]) < 1e-10


@pytest.mark.parametrize("patch,key", [
    ({"scene": {"walker": {"leg_com": 2.0}}}, "scene.walker"),
    ({"scene": {"walker": {"hip_mass": "ten"}}}, "scene.walker.hip_mass"),
    ({"initial": {"stance": -0.2}}, "initial"),
    ({"design": {"slope": 0.05, "rise": 0.1, "tread": 0.3}}, "design"),
    ({"design": {"slop": 0.05}}, "design.slop"),
    ({"scene": {"friction": -1.0}}, "scene.friction"),
])
def test_bad_input_names_the_key(patch, key):
    data = tomllib.loads((PROBLEMS / "compass_gait_ramp.toml").read_text())
    for table, values in patch.items():
        if table == "initial" or table == "design":
            data[table] = dict(values)
        else:
            for k, v in values.items():
                if isinstance(v, dict):
                    data[table][k] = {**data[table][k], **v}
                else:
                    data[table][k] = v
    with pytest.raises(SpecError) as err:
        read_tables(data, "x.toml")
    assert err.value.key.startswith(key)
    assert "x.toml" in str(err.value)


@pytest.mark.parametrize("quantity, key", [("rise", "tolerances.rise"),
                                           ("tread", "tolerances.tread")])
def test_a_tolerance_the_ramp_has_not_names_its_key(quantity, key):
    """A ramp has no rise; where a foot lands on a tread is not followed: both refused."""
    from pdm_design.commands.yield_ import spec_tolerances
    from pdm_design.spec import parse_spec

    text = (PROBLEMS / "compass_gait_rough.toml").read_text().replace(
        'slope = { value = 0.007, applies_to = "each" }',
        f'{quantity} = {{ value = 0.001, applies_to = "each" }}')
    with pytest.raises(SpecError) as err:
        spec_tolerances(parse_spec(tomllib.loads(text), "x.toml"), "x.toml")
    assert err.value.key.startswith(key)
