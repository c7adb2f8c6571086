"""The elastic lattice: exact damped-oscillator steps, and read-only views of its state."""
import numpy as np
import pytest

import deform


def oscillator(x0, t, k, zeta, m):
    w0 = np.sqrt(k / m)
    wd = w0 * np.sqrt(1 - zeta**2)
    return x0 * np.exp(-zeta * w0 * t) * (np.cos(wd * t) + zeta * w0 / wd * np.sin(wd * t))


def test_points_spring_back_like_a_damped_oscillator():
    rest = np.zeros((3, 3), np.float32)
    start = np.array([[1, 0, 0], [0, 2, 0], [0, 0, -1]], np.float32)
    k, zeta, m = 150.0, 0.2, 1.0
    lattice = deform.ElasticLattice(start, stiffness=k, damping_ratio=zeta, mass=m)
    dt, t = 1 / 120, 0.0
    for _ in range(40):
        lattice.step(dt, rest)
        t += dt
        np.testing.assert_allclose(lattice.positions, oscillator(start, t, k, zeta, m), atol=1e-4)
    assert lattice.positions[0, 0] < 0  # under-damped: it overshot


def test_views_share_memory_and_are_read_only():
    rest = np.zeros((2, 3), np.float32)
    lattice = deform.ElasticLattice(np.ones((2, 3), np.float32))
    view = lattice.positions
    assert np.shares_memory(view, lattice.positions)
    assert not view.flags.writeable
    lattice.step(0.1, rest)
    np.testing.assert_array_equal(view, lattice.positions)
    lattice.reset(rest)
    np.testing.assert_array_equal(view, rest)
    np.testing.assert_array_equal(lattice.velocities, 0)


def test_bad_parameters_raise():
    with pytest.raises(deform.Error):
        deform.ElasticLattice(np.zeros((2, 3), np.float32), stiffness=-1)
