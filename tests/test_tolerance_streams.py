"""Each toleranced quantity's random stream: the first scenes' quantities keep the streams that
SeedSequence.spawn gave them in a fixed order; any other name has its own, from its name."""

from __future__ import annotations

import hashlib

import numpy as np
from scipy.special import ndtri

from pdm_design.tolerance_model import Tolerance
from pdm_design.tolerances.draw import FIRST_STREAMS, draw

SPAWNED = ("pivot_x", "pivot_y", "link_length", "back_stop", "palm_mass", "friction",
           "object_mass", "object_width", "feed_x", "feed_speed", "rise", "tread",
           "restitution", "launch_speed", "launch_x", "link_mass", "pivot_friction")


def _uniform(child, count):
    return np.random.Generator(np.random.PCG64(child)).random(count) + 2.0 ** -54


def test_the_first_quantities_draw_from_the_spawned_children_in_their_order():
    assert FIRST_STREAMS == SPAWNED
    children = np.random.SeedSequence(11).spawn(len(SPAWNED))
    for i, name in enumerate(SPAWNED):
        tol = Tolerance(name, "lot", 0.3)
        got = draw([tol], 4, 1, 11)[name]
        np.testing.assert_array_equal(got, (0.3 / 3.0) * ndtri(_uniform(children[i], 4)))


def test_a_new_quantity_draws_from_the_child_keyed_by_its_name():
    key = 2 ** 32 + int.from_bytes(hashlib.sha256(b"spoke_length").digest()[:4], "big")
    child = np.random.SeedSequence(entropy=5, spawn_key=(key,))
    tol = Tolerance("spoke_length", "each", 0.003, distribution="uniform")
    got = draw([tol], 2, 3, 5)["spoke_length"]
    np.testing.assert_array_equal(got.ravel(), 0.003 * (2.0 * _uniform(child, 6) - 1.0))


def test_a_new_quantity_leaves_the_others_draws_alone_and_differs_from_them():
    rise = Tolerance("rise", "each", 0.001)
    alone = draw([rise], 5, 4, 0)["rise"]
    both = draw([rise, Tolerance("spoke_length", "each", 0.001)], 5, 4, 0)
    np.testing.assert_array_equal(both["rise"], alone)
    assert not np.allclose(both["spoke_length"], alone)
