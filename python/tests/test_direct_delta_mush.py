"""Direct Delta Mush from Python: the rest pose given back, a rigid motion kept rigid, normals, and bad input."""
import numpy as np
import pytest

import deform


def test_rest_pose_and_rigid_motion(builtin_model):
    ddm = deform.DirectDeltaMush(builtin_model)
    assert len(ddm) == builtin_model.point_count and ddm.influences >= len(ddm)
    skeleton = builtin_model.skeleton
    _, palette = deform.forward_kinematics(skeleton, skeleton.bind_pose())
    rest = builtin_model.positions
    size = np.linalg.norm(rest.max(axis=0) - rest.min(axis=0))
    assert np.abs(ddm.skin(palette) - rest).max() <= 1e-6 * size
    # The whole skeleton turned 90 degrees about z and moved: every point and normal follows rigidly.
    g = np.array([[0, -1, 0, 0.5], [1, 0, 0, -2.0], [0, 0, 1, 1.0], [0, 0, 0, 1]], np.float32)
    normals = np.tile(np.array([[0.6, 0.0, 0.8]], np.float32), (len(ddm), 1))
    moved, turned = ddm.skin(g @ palette, normals=normals)
    np.testing.assert_allclose(moved, rest @ g[:3, :3].T + g[:3, 3], atol=1e-5 * size)
    np.testing.assert_allclose(turned, normals @ g[:3, :3].T, atol=1e-5)


def test_a_bent_elbow_differs_from_lbs(builtin_model):
    skeleton = builtin_model.skeleton
    pose = skeleton.bind_pose()
    skeleton.set_euler(pose, "forearm_l", [110, 0, 0])
    _, palette = deform.forward_kinematics(skeleton, pose)
    ddm = deform.DirectDeltaMush(builtin_model, iterations=3, step=3.0)
    got = ddm.skin(palette)
    lbs = deform.skin(builtin_model.positions, builtin_model.bone_indices, builtin_model.bone_weights, palette)
    gap = np.linalg.norm(got - lbs, axis=1)
    assert gap.max() > 1e-3 and (gap > 1e-3).sum() < len(gap) / 2


def test_bad_settings_and_palettes_are_refused(builtin_model):
    with pytest.raises(deform.Error, match="iterations"):
        deform.DirectDeltaMush(builtin_model, iterations=0)
    ddm = deform.DirectDeltaMush(builtin_model)
    with pytest.raises(deform.Error, match="palette is too small"):
        ddm.skin(np.broadcast_to(np.eye(4, dtype=np.float32), (3, 4, 4)))
