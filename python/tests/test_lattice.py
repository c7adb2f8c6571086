"""Lattices deform any (N, 3) float32 point cloud: identity at rest, Bernstein weights when a point moves."""
from math import comb

import numpy as np
import pytest

import deform

LATTICES = [deform.BezierLattice, deform.BsplineLattice]


@pytest.fixture
def cloud():
    return np.random.default_rng(1).uniform(-1, 1, size=(2000, 3)).astype(np.float32)


@pytest.mark.parametrize("kind", LATTICES)
def test_a_lattice_at_rest_is_the_identity(kind, cloud):
    lattice = kind.around(cloud)
    np.testing.assert_allclose(lattice.deform(cloud), cloud, atol=1e-5)
    np.testing.assert_allclose(lattice.control_points, lattice.rest_points)


def test_index_outside_the_lattice_raises(cloud):
    lattice = deform.BezierLattice.around(cloud, degree=(2, 3, 2))
    assert lattice.index(2, 3, 2) == len(lattice.control_points) - 1
    for bad in ((-1, 0, 0), (0, -1, 0), (0, 0, -1), (3, 0, 0), (0, 4, 0), (0, 0, 3)):
        with pytest.raises(IndexError, match="outside the lattice"):
            lattice.index(*bad)


def bernstein(n, i, t):
    return comb(n, i) * t**i * (1 - t) ** (n - i)


def test_moving_one_control_point_moves_points_by_its_bernstein_weight(cloud):
    lattice = deform.BezierLattice.around(cloud, degree=(2, 3, 2))
    i, j, k = 1, 2, 0
    d = np.array([0.1, -0.2, 0.3], np.float32)
    lattice.control_points[lattice.index(i, j, k)] += d
    moved = lattice.deform(cloud)
    u, v, w = lattice.to_lattice(cloud).astype(np.float64).T
    weight = bernstein(2, i, u) * bernstein(3, j, v) * bernstein(2, k, w)
    np.testing.assert_allclose(moved - cloud, weight[:, None] * d, atol=2e-5)
    lattice.reset()
    np.testing.assert_allclose(lattice.deform(cloud), cloud, atol=1e-5)


def test_control_points_are_a_view_of_the_lattice(cloud):
    lattice = deform.BezierLattice.around(cloud)
    view = lattice.control_points
    assert view.shape == (64, 3) and view.flags.writeable
    assert np.shares_memory(view, lattice.control_points)
    view += 1.0  # translating every control point translates the cloud
    np.testing.assert_allclose(lattice.deform(cloud), cloud + 1.0, atol=1e-5)


@pytest.mark.parametrize("kind", LATTICES)
def test_a_binding_is_reused_and_outside_points_stay(kind, cloud):
    lattice = kind([-0.5, -0.5, -0.5], [1, 1, 1])
    binding = lattice.bind(cloud)
    inside = np.all(np.abs(cloud) <= 0.5, axis=1)
    assert binding.bound_count == inside.sum()
    np.testing.assert_array_equal(binding.vertices, np.flatnonzero(inside))
    lattice.control_points[:] *= 2.0
    moved = lattice.deform(cloud, binding)
    np.testing.assert_array_equal(moved[~inside], cloud[~inside])
    np.testing.assert_allclose(moved[inside], 2.0 * cloud[inside], atol=1e-5)
    np.testing.assert_array_equal(moved, lattice.deform(cloud))


@pytest.mark.parametrize("kind", LATTICES)
def test_direct_manipulation_puts_the_point_on_the_target(kind):
    lattice = kind([0, 0, 0], [2, 2, 2])
    uvw = np.array([0.3, 0.6, 0.5], np.float32)
    target = np.array([0.9, 1.0, 1.4], np.float32)
    lattice.move_point(uvw, target)
    np.testing.assert_allclose(lattice.evaluate(uvw[None])[0], target, atol=1e-4)


def test_degree_out_of_range_raises():
    with pytest.raises(deform.Error):
        deform.BezierLattice([0, 0, 0], [1, 1, 1], degree=99)
    with pytest.raises(deform.Error):
        deform.BezierLattice([0, 0, 0], [1, 0, 1])
