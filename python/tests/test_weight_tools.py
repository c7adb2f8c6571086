"""The weight tools on a Model, in place: each checked for what it promises on the built-in character."""
import numpy as np
import pytest

import deform


def sums_are_one(model):
    np.testing.assert_allclose(model.bone_weights.sum(axis=1), 1.0, atol=1e-5)


def test_select_bones_and_glob(builtin_model):
    mask = deform.select_bones(builtin_model.skeleton, ["hand_?", "forearm_*"], ["*_r"])
    names = builtin_model.skeleton.names
    assert [names[i] for i in np.flatnonzero(mask)] == ["forearm_l", "hand_l"]
    assert deform.glob_match("thumb[12]_l", "thumb2_l")
    assert not deform.glob_match("thumb[12]_l", "thumb3_l")
    with pytest.raises(deform.Error, match="pattern 'pelvis': matches no bone"):
        deform.select_bones(builtin_model.skeleton, ["pelvis"])
    assert deform.mirrored_bone_name("hand_l") == "hand_r"
    assert deform.mirrored_bone_name("spine") is None
    assert deform.mirrored_bone_name("ArmLinks", [("Links", "Rechts")]) == "ArmRechts"


def test_prune_limit_normalize(model):
    model.bone_weights[:] *= 2.0
    deform.normalize_weights(model)
    sums_are_one(model)
    removed = deform.prune_weights(model, 0.25)
    assert removed > 0
    sums_are_one(model)
    w = model.bone_weights
    assert np.all((w == 0) | (w >= 0.25 * (1 - 1e-6)))
    deform.limit_influences(model, 1)
    assert np.all(model.bone_weights[:, 1:] == 0)
    np.testing.assert_array_equal(model.bone_weights[:, 0], 1.0)


def test_smooth_lowers_the_gradient(model):
    before = deform.weight_gradient_energy(model)
    deform.smooth_weights(model, iterations=3)
    sums_are_one(model)
    assert deform.weight_gradient_energy(model) < before
    with pytest.raises(deform.Error, match="factor"):
        deform.smooth_weights(model, factor=0.0)


def test_mirror_flip_twice_is_the_input(model, builtin_model):
    result = deform.mirror_weights(model)
    assert result["axis"] == "x" and result["bone_pairs"] == 12 and result["points"] == model.point_count
    sums_are_one(model)
    assert not np.array_equal(model.bone_indices, builtin_model.bone_indices)
    deform.mirror_weights(model, "flip")
    np.testing.assert_allclose(model.bone_weights, builtin_model.bone_weights, atol=1e-5)
    np.testing.assert_array_equal(model.bone_indices[model.bone_weights > 1e-4],
                                  builtin_model.bone_indices[model.bone_weights > 1e-4])
    with pytest.raises(deform.Error, match="has no mirror point"):
        deform.mirror_weights(model, axis="y")
    with pytest.raises(deform.Error, match="mode 'sideways'"):
        deform.mirror_weights(model, "sideways")


def test_bad_weights_are_refused(model):
    model.bone_weights[3, 1] = np.nan
    with pytest.raises(deform.Error, match="point 3: weight"):
        deform.normalize_weights(model)
