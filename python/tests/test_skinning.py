"""Skinning against a NumPy reference, forward kinematics, and the no-copy paths."""
import numpy as np
import pytest

import deform


def random_rotations(rng, count):
    q, r = np.linalg.qr(rng.normal(size=(count, 3, 3)))
    q *= np.sign(np.diagonal(r, axis1=1, axis2=2))[:, None, :]
    q[np.linalg.det(q) < 0, :, 0] *= -1  # proper rotations
    return q


def random_palette(rng, bones, scale=False):
    m = np.zeros((bones, 4, 4), np.float32)
    m[:, :3, :3] = random_rotations(rng, bones)
    if scale:
        m[:, :3, :3] *= rng.uniform(0.5, 2.0, size=(bones, 1, 1))
    m[:, :3, 3] = rng.normal(size=(bones, 3))
    m[:, 3, 3] = 1
    return m


def random_skin(rng, n, bones):
    positions = rng.normal(size=(n, 3)).astype(np.float32)
    indices = rng.integers(0, bones, size=(n, 4)).astype(np.uint16)
    weights = rng.uniform(0, 1, size=(n, 4)).astype(np.float32)
    weights /= weights.sum(axis=1, keepdims=True)
    return positions, indices, weights


def lbs_reference(positions, indices, weights, palette):
    blended = np.einsum("nk,nkij->nij", weights.astype(np.float64), palette[indices].astype(np.float64))
    return np.einsum("nij,nj->ni", blended[:, :3, :3], positions) + blended[:, :3, 3]


@pytest.mark.parametrize("n", [1, 17, 1000])
def test_lbs_matches_numpy_reference(n):
    rng = np.random.default_rng(n)
    positions, indices, weights = random_skin(rng, n, 8)
    palette = random_palette(rng, 8, scale=True)
    got = deform.skin(positions, indices, weights, palette, "lbs")
    want = lbs_reference(positions, indices, weights, palette)
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-5)


def test_dqs_equals_lbs_for_a_single_rigid_influence():
    rng = np.random.default_rng(7)
    positions, indices, _ = random_skin(rng, 200, 6)
    weights = np.zeros((200, 4), np.float32)
    weights[:, 0] = 1
    palette = random_palette(rng, 6)
    dqs = deform.skin(positions, indices, weights, palette, "dqs")
    np.testing.assert_allclose(dqs, lbs_reference(positions, indices, weights, palette), atol=1e-5)


def test_dqs_keeps_distance_to_the_axis_under_twist():
    # Two bones twisted 180 degrees apart about Y: LBS collapses a point halfway onto the axis, DQS keeps its radius.
    twist = np.eye(4, dtype=np.float32)
    twist[0, 0] = twist[2, 2] = -1
    palette = np.stack([np.eye(4, dtype=np.float32), twist])
    positions = np.array([[1, 0, 0]], np.float32)
    indices = np.array([[0, 1, 0, 0]], np.uint16)
    weights = np.array([[0.5, 0.5, 0, 0]], np.float32)
    lbs = deform.skin(positions, indices, weights, palette, "lbs")
    dqs = deform.skin(positions, indices, weights, palette, "dqs")
    assert np.linalg.norm(lbs[0, [0, 2]]) < 1e-6
    assert np.linalg.norm(dqs[0, [0, 2]]) == pytest.approx(1.0, abs=1e-5)


def test_skin_writes_into_out_without_copying():
    rng = np.random.default_rng(3)
    positions, indices, weights = random_skin(rng, 64, 4)
    palette = random_palette(rng, 4)
    out = np.empty_like(positions)
    result = deform.skin(positions, indices, weights, palette, out=out)
    assert result is out
    np.testing.assert_allclose(out, lbs_reference(positions, indices, weights, palette), atol=1e-5)
    with pytest.raises(deform.Error):
        deform.skin(positions, indices, weights, palette, out=np.empty((64, 3), np.float64))


def test_other_layouts_are_converted():
    rng = np.random.default_rng(4)
    positions, indices, weights = random_skin(rng, 50, 4)
    palette = random_palette(rng, 4)
    want = deform.skin(positions, indices, weights, palette)
    wide = np.zeros((50, 4), np.float64)
    wide[:, :3] = positions
    got = deform.skin(wide[:, :3], indices.astype(np.int64), weights.astype(np.float64), palette.astype(np.float64))
    np.testing.assert_allclose(got, want, atol=1e-6)


def test_forward_kinematics_of_the_bind_pose(builtin_model):
    skeleton = builtin_model.skeleton
    world, palette = deform.forward_kinematics(skeleton, skeleton.bind_pose())
    assert world.shape == (33, 4, 4)
    np.testing.assert_allclose(world, skeleton.bind_world, atol=1e-5)
    np.testing.assert_allclose(palette, np.broadcast_to(np.eye(4), palette.shape), atol=1e-5)
    # Row-major convention: the translation is the last column, the bottom row is 0 0 0 1.
    np.testing.assert_allclose(world[:, 3], np.broadcast_to([0, 0, 0, 1], (33, 4)))


def test_model_skinned_by_a_posed_skeleton_matches_reference(model):
    skeleton = model.skeleton
    pose = skeleton.bind_pose()
    skeleton.set_euler(pose, "forearm_l", [0, 0, 60])
    skeleton.set_euler(pose, "spine", [10, 20, 0])
    _, palette = deform.forward_kinematics(skeleton, pose)
    got = deform.skin(model.positions, model.bone_indices, model.bone_weights, palette)
    want = lbs_reference(model.positions, model.bone_indices, model.bone_weights, palette)
    np.testing.assert_allclose(got, want, atol=1e-5)
    assert np.abs(got - model.positions).max() > 0.05


def test_model_arrays_are_views(model):
    assert np.shares_memory(model.positions, model.positions)
    model.positions[0] = (1, 2, 3)
    np.testing.assert_array_equal(model.positions[0], [1, 2, 3])
    assert model.bone_indices.dtype == np.uint16 and model.bone_weights.shape == (model.point_count, 4)
    assert model.triangles.dtype == np.uint32


def test_pose_arrays_are_writeable_views(builtin_model):
    pose = builtin_model.skeleton.bind_pose()
    rotations = pose.rotations
    assert rotations.shape == (33, 4) and np.shares_memory(rotations, pose.rotations)
    before = rotations[4].copy()
    builtin_model.skeleton.set_euler(pose, "head", [0, 30, 0])
    assert not np.allclose(rotations[4], before)  # the view sees the change
    np.testing.assert_allclose(np.linalg.norm(rotations, axis=1), 1, atol=1e-6)
    assert pose.translations.shape == (33, 3)
