"""Pose-space correctives from Python: a sculpted pad at a bent elbow, its driver, the Character giving it back."""
import numpy as np
import pytest

import deform


def test_a_sculpt_comes_back_at_its_pose_and_fades_at_rest():
    model = deform.builtin_character()
    skeleton = model.skeleton
    bent = skeleton.bind_pose()
    skeleton.set_euler(bent, "forearm_l", [120.0, 0.0, 0.0])
    plain = deform.Character(model)
    plain.pose = bent
    plain.update(0.0)
    sculpt = np.array(plain.positions)
    elbow = np.array(plain.bone_position("forearm_l"))
    near = np.linalg.norm(sculpt - elbow, axis=1) < 0.08
    sculpt[near, 1] += 0.01
    target = deform.add_corrective(model, plain.palette, sculpt, tolerance=1e-6, name="elbow_pad")
    assert target == 0
    driver = deform.bind_pose_driver(skeleton, ["upperarm_l", "forearm_l"], [skeleton.bind_pose(), plain.pose],
                                     np.array([[0.0], [1.0]], np.float32))
    assert driver.shape_count == 1 and driver.pose_count == 2 and driver.radius > 0
    assert driver.weights(plain.pose)[0] == pytest.approx(1.0, abs=1e-4)
    hero = deform.Character(model)
    hero.add_pose_driver(driver, [0])
    hero.pose = plain.pose
    hero.update(0.0)
    assert np.abs(np.asarray(hero.positions) - sculpt).max() < 1e-4
    hero.pose = skeleton.bind_pose()
    hero.update(0.0)
    assert hero.morph_weight(0) == pytest.approx(0.0, abs=1e-4)
    with pytest.raises(deform.Error):
        hero.add_pose_driver(driver, [3])
    with pytest.raises(deform.Error, match="kernel"):
        deform.bind_pose_driver(skeleton, ["forearm_l"], [bent], np.ones((1, 1), np.float32), kernel="cubic")


def test_driven_weights_keyed_into_a_clip_and_written_as_gltf(tmp_path):
    model = deform.builtin_character()
    skeleton = model.skeleton
    bent = skeleton.bind_pose()
    skeleton.set_euler(bent, "forearm_l", [100.0, 0.0, 0.0])
    plain = deform.Character(model)
    plain.pose = bent
    plain.update(0.0)
    sculpt = np.array(plain.positions)
    sculpt[np.linalg.norm(sculpt - np.array(plain.bone_position("forearm_l")), axis=1) < 0.08, 2] -= 0.01
    deform.add_corrective(model, plain.palette, sculpt, tolerance=1e-6, name="elbow_pad")
    driver = deform.bind_pose_driver(skeleton, ["forearm_l"], [skeleton.bind_pose(), plain.pose],
                                     np.array([[0.0], [1.0]], np.float32))
    hero = deform.Character(model)
    hero.add_pose_driver(driver, [0])
    run = [clip for clip in deform.builtin_clips(model) if clip.name == "run"][0]
    assert run.morph_channel_targets == []
    keyed = hero.with_driven_weights(run, 20.0)
    assert keyed.morph_channel_targets == [0] and keyed.name == "run"
    written = deform.write_gltf(str(tmp_path / "run.glb"), hero.model, [keyed])
    assert written["warnings"] == []
    with pytest.raises(deform.Error, match="frames_per_second"):
        hero.with_driven_weights(run, 0.0)
