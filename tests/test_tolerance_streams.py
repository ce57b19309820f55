"""Each toleranced quantity's random stream: the first scenes' quantities keep the streams that
SeedSequence.spawn gave them in a fixed order (their scene's Scene.stream_keys); any other name
has its own, from its name."""

from __future__ import annotations

import hashlib

import numpy as np
import pytest
from scipy.special import ndtri

from pdm_design import plugin
from pdm_design.scenes.common import FIRST_STREAMS
from pdm_design.tolerance_model import Tolerance
from pdm_design.tolerances.draw import draw, stream_key

# The order the streams were spawned in before they were keyed by name, as it stood then: the
# builds of every quantity named here are drawn from child i of SeedSequence(seed).spawn.
SPAWNED = ("pivot_x", "pivot_y", "link_length", "back_stop", "palm_mass", "friction",
           "object_mass", "object_width", "feed_x", "feed_speed", "rise", "tread",
           "restitution", "launch_speed", "launch_x", "link_mass", "pivot_friction")


def _named(name: str) -> int:
    return 2 ** 32 + int.from_bytes(hashlib.sha256(name.encode()).digest()[:4], "big")


def _uniform(child, count):
    return np.random.Generator(np.random.PCG64(child)).random(count) + 2.0 ** -54


def test_the_first_quantities_draw_from_the_spawned_children_in_their_order():
    assert FIRST_STREAMS == SPAWNED
    children = np.random.SeedSequence(11).spawn(len(SPAWNED))
    row = plugin.scene_kind("manipulators")
    for i, name in enumerate(SPAWNED):
        scene = row if name in row.quantities() else plugin.scene_kind("stairs")
        tol = Tolerance(name, "lot", 0.3)
        got = draw([tol], 4, 1, 11, scene=scene)[name]
        np.testing.assert_array_equal(got, (0.3 / 3.0) * ndtri(_uniform(children[i], 4)))


@pytest.mark.parametrize("kind", plugin.kinds())
def test_every_quantity_of_every_scene_keeps_its_stream_key(kind):
    # the key each quantity's builds were drawn with before the scenes declared them: its place
    # in the spawned order, any other name the key of its name
    scene = plugin.scene_kind(kind)
    quantities = scene.quantities()
    assert quantities and set(scene.stream_keys) <= set(quantities)
    for name in quantities:
        want = SPAWNED.index(name) if name in SPAWNED else _named(name)
        assert stream_key(name, scene) == want == stream_key(name, _Kind(kind)), name


class _Kind:
    """A scene dataclass as draw takes it (anything with the scene's kind)."""

    def __init__(self, kind: str):
        self.kind = kind


def test_every_spawned_name_is_a_quantity_some_scene_keeps_it_for():
    declared = {name for kind in plugin.kinds()
                for name in plugin.scene_kind(kind).stream_keys}
    assert declared == set(SPAWNED)


def test_a_new_quantity_draws_from_the_child_keyed_by_its_name():
    child = np.random.SeedSequence(entropy=5, spawn_key=(_named("spoke_length"),))
    tol = Tolerance("spoke_length", "each", 0.003, distribution="uniform")
    got = draw([tol], 2, 3, 5, scene=plugin.scene_kind("rimless_wheel"))["spoke_length"]
    np.testing.assert_array_equal(got.ravel(), 0.003 * (2.0 * _uniform(child, 6) - 1.0))


def test_a_new_quantity_leaves_the_others_draws_alone_and_differs_from_them():
    rise = Tolerance("rise", "each", 0.001)
    wheel = plugin.scene_kind("rimless_wheel")
    alone = draw([rise], 5, 4, 0, scene=wheel)["rise"]
    both = draw([rise, Tolerance("spoke_length", "each", 0.001)], 5, 4, 0, scene=wheel)
    np.testing.assert_array_equal(both["rise"], alone)
    assert not np.allclose(both["spoke_length"], alone)
