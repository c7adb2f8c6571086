"""Blending, additive layers and root motion from Python (deform.blend, additive_delta, make_additive_clip,
root_motion) on the built-in character's clips, against NumPy math done here."""
import numpy as np
import pytest

import deform


def clip_named(model, name):
    return [c for c in deform.builtin_clips(model) if c.name == name][0]


def sampled(model, clip, t):
    pose = model.skeleton.bind_pose()
    clip.sample(t, pose)
    return pose


def same_rotations(a, b, tolerance=1e-5):
    """Per bone: q and -q are one rotation."""
    return np.all(np.minimum(np.linalg.norm(a - b, axis=1), np.linalg.norm(a + b, axis=1)) < tolerance)


def test_blend_matches_numpy_nlerp(builtin_model):
    walk, run = clip_named(builtin_model, "walk"), clip_named(builtin_model, "run")
    rest = builtin_model.skeleton.bind_pose()
    a, b = sampled(builtin_model, walk, 0.3), sampled(builtin_model, run, 0.2)
    out = deform.blend([(a, 0.7), (b, 0.3)], rest)
    qa, qb = a.rotations.astype(np.float64), b.rotations.astype(np.float64)
    sign = np.where(np.sum(qa * qb, axis=1) < 0, -1.0, 1.0)[:, None]
    q = 0.7 * qa + 0.3 * sign * qb
    q /= np.linalg.norm(q, axis=1)[:, None]
    assert same_rotations(out.rotations, q)
    assert np.allclose(out.translations, 0.7 * a.translations + 0.3 * b.translations, atol=1e-6)
    # Weights scaled together: the same pose.
    again = deform.blend([(a, 7.0), (b, 3.0)], rest)
    assert same_rotations(out.rotations, again.rotations)


def test_mask_takes_bones_from_one_layer(builtin_model):
    walk, wave = clip_named(builtin_model, "walk"), clip_named(builtin_model, "wave")
    rest = builtin_model.skeleton.bind_pose()
    a, b = sampled(builtin_model, walk, 0.4), sampled(builtin_model, wave, 0.4)
    upper = np.zeros(len(rest), dtype=np.float32)
    upper[len(rest) // 2:] = 1.0
    out = deform.blend([(a, 1.0, 1.0 - upper), (b, 1.0, upper)], rest)
    assert same_rotations(out.rotations[upper == 1], b.rotations[upper == 1], 1e-6)
    assert same_rotations(out.rotations[upper == 0], a.rotations[upper == 0], 1e-6)
    with pytest.raises(deform.Error) as info:
        deform.blend([(a, 1.0, np.ones(3, dtype=np.float32))], rest)
    assert info.value.kind == "status"
    with pytest.raises(deform.Error):
        deform.blend([(a, -1.0)], rest)


def test_additive_restores_the_pose(builtin_model):
    walk = clip_named(builtin_model, "walk")
    rest = builtin_model.skeleton.bind_pose()
    reference, pose = sampled(builtin_model, walk, 0.0), sampled(builtin_model, walk, 0.5)
    delta = deform.additive_delta(reference, pose)
    out = deform.blend([(reference, 1.0)], rest, additive=[(delta, 1.0)])
    assert same_rotations(out.rotations, pose.rotations)
    assert np.allclose(out.translations, pose.translations, atol=1e-6)
    # The additive clip from the first frame samples to the same delta.
    additive = deform.make_additive_clip(walk)
    sampled_delta = builtin_model.skeleton.bind_pose()
    sampled_delta.rotations[:] = [0, 0, 0, 1]
    sampled_delta.translations[:] = 0
    additive.sample(0.5, sampled_delta)
    assert same_rotations(sampled_delta.rotations, delta.rotations, 1e-5)


def test_root_motion_composes_over_loops(builtin_model):
    walk = clip_named(builtin_model, "walk")
    hips = 0
    t1, yaw1 = deform.root_motion(walk, hips, 0.2, 1.7)
    t2, yaw2 = deform.root_motion(walk, hips, 1.7, 3.1)
    t3, yaw3 = deform.root_motion(walk, hips, 0.2, 3.1)
    c, s = np.cos(yaw1), np.sin(yaw1)
    rotated = np.array([c * t2[0] + s * t2[2], t2[1], -s * t2[0] + c * t2[2]])  # about +Y by yaw1
    assert np.allclose(t1 + rotated, t3, atol=1e-5)
    assert abs(yaw1 + yaw2 - yaw3) < 1e-5
    assert abs(t3[1]) < 1e-6  # horizontal
    pose = sampled(builtin_model, walk, 3.1)
    deform.root_motion(walk, hips, 0.0, 3.1, pose=pose)
    assert abs(pose.translations[hips][0]) < 1e-6 and abs(pose.translations[hips][2]) < 1e-6
