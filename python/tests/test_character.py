"""The Character: reach, stretch, release, and positions as views of its storage."""
import gc

import numpy as np
import pytest

import deform

TARGET = np.array([1.6, 1.5, 0.3], np.float32)


@pytest.fixture
def hero():
    return deform.Character.builtin()


def settle(character, seconds, dt=1 / 60):
    for _ in range(int(round(seconds / dt))):
        character.update(dt)


def test_reach_stretches_to_the_target_and_release_springs_back(hero):
    hero.update(0.0)
    rest = hero.positions.copy()
    result = hero.reach("hand_l", TARGET)
    assert result.residual > 0.5 and result.stretch == pytest.approx(result.residual, rel=0.05)
    settle(hero, 3.0)
    hand = np.array(hero.bone_position("hand_l"))
    assert np.linalg.norm(hand - TARGET) <= 0.01 * result.residual + 1e-3
    assert hero.stretch == pytest.approx(result.stretch, rel=0.02)
    hero.release()
    settle(hero, 4.0)
    assert abs(hero.stretch) < 0.01 * result.stretch
    assert np.abs(hero.positions - rest).max() > 0.05  # the reached pose stays


def test_positions_are_a_read_only_view_that_keeps_the_character(hero):
    hero.update(0.0)
    view = hero.positions
    assert view.shape == (hero.point_count, 3) and view.dtype == np.float32
    assert not view.flags.writeable
    assert np.shares_memory(view, hero.positions)
    before = view.copy()
    hero.reach("hand_l", TARGET)
    settle(hero, 0.5)
    assert not np.array_equal(view, before)  # the same storage, updated
    expected = view.copy()
    del hero
    gc.collect()
    np.testing.assert_array_equal(view, expected)


def test_normals_and_control_points(hero):
    hero.update(0.0)
    normals = hero.normals()
    np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1, atol=1e-4)
    # The render mesh they belong to: each triangle's own normal, from the deformed points, agrees with its corners'.
    model = hero.model
    assert normals.shape == (model.vertex_count, 3) and model.vertex_points.shape == (model.vertex_count,)
    assert model.uvs is None or model.uvs.shape == (model.vertex_count, 2)
    corners = hero.positions[model.vertex_points[model.vertex_triangles]]
    faces = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    faces /= np.linalg.norm(faces, axis=1, keepdims=True)
    cosines = np.einsum("tj,tcj->tc", faces, normals[model.vertex_triangles])
    assert cosines.mean() > 0.95
    np.testing.assert_array_equal(model.vertex_points[model.vertex_triangles], model.triangles)
    assert hero.lattice_count == 3
    assert hero.control_points(0).shape == (64, 3)
    with pytest.raises(deform.Error):
        hero.control_points(3)


def test_settings_and_pose(hero):
    hero.skinning = "dqs"
    hero.reach_solver = "two_bone"
    hero.reach_pole = [0.5, 1.4, -1.0]
    assert hero.reach_pole == pytest.approx((0.5, 1.4, -1.0))
    result = hero.reach("hand_l", [0.9, 1.2, 0.2])
    settle(hero, 2.0)
    distance = np.linalg.norm(np.array(hero.bone_position("hand_l")) - [0.9, 1.2, 0.2])
    assert distance == pytest.approx(result.distance, abs=0.01)
    with pytest.raises(deform.Error):
        hero.skinning = "magic"
    pose = hero.pose
    hero.skeleton.set_euler(pose, "head", [0, 40, 0])
    hero.pose = pose
    np.testing.assert_allclose(hero.pose.rotations[4], pose.rotations[4], atol=1e-6)
    with pytest.raises(deform.Error):
        hero.reach("hips", TARGET)


def test_a_character_from_loaded_files(native_paths):
    model = deform.load_model(*native_paths)
    hero = deform.Character(model, deform.builtin_rig(model))
    hero.reach("hand_l", TARGET)
    settle(hero, 3.0)
    assert np.linalg.norm(np.array(hero.bone_position("hand_l")) - TARGET) < 0.02
    plain = deform.Character(model)
    assert plain.lattice_count == 0


def test_delta_mush_smooths_a_bent_elbow_and_gives_the_rest_back():
    plain, mushed = deform.Character.builtin(), deform.Character.builtin()
    assert mushed.delta_mush_iterations == 0
    mushed.set_delta_mush(iterations=10, step=0.5)
    assert mushed.delta_mush_iterations == 10
    plain.update(0.0)
    mushed.update(0.0)
    np.testing.assert_allclose(mushed.positions, plain.positions, atol=2e-6)  # the rest pose back
    for c in (plain, mushed):
        pose = c.pose
        c.skeleton.set_euler(pose, "forearm_l", [110, 0, 0])
        c.pose = pose
        c.update(0.0)
    assert np.abs(mushed.positions - plain.positions).max() > 1e-3
    mushed.set_delta_mush(10, 0.5, np.zeros(mushed.point_count, np.float32))  # every point kept as skinned
    mushed.update(0.0)
    np.testing.assert_array_equal(mushed.positions, plain.positions)
    for bad in ({"iterations": -1}, {"step": float("nan")}, {"mask": np.ones(3, np.float32)}):
        with pytest.raises(deform.Error):
            mushed.set_delta_mush(**bad)
    mushed.clear_delta_mush()
    assert mushed.delta_mush_iterations == 0


def test_direct_delta_mush_reduced_variant():
    full, reduced = deform.Character.builtin(), deform.Character.builtin()
    full.set_direct_delta_mush()
    reduced.set_direct_delta_mush(variant="reduced")
    assert full.direct_delta_mush_variant == "full" and reduced.direct_delta_mush_variant == "reduced"
    assert reduced.direct_delta_mush_bound
    reduced.update(0.0)
    np.testing.assert_allclose(reduced.positions, reduced.model.positions, atol=2e-5)  # the rest pose back
    for c in (full, reduced):
        pose = c.pose
        c.skeleton.set_euler(pose, "forearm_l", [150, 0, 0])
        c.pose = pose
        c.update(0.0)
    gap = np.abs(full.positions - reduced.positions).max()
    assert 1e-5 < gap < 0.1  # near the full form, not the same
    with pytest.raises(deform.Error):
        reduced.set_direct_delta_mush(variant="v2")
    assert reduced.direct_delta_mush_variant == "reduced"  # kept
    reduced.clear_direct_delta_mush()
    assert reduced.direct_delta_mush_variant == "" and not reduced.direct_delta_mush_bound


def test_direct_delta_mush_skins_in_place_of_lbs_and_matches_the_job():
    lbs, ddm = deform.Character.builtin(), deform.Character.builtin()
    assert not ddm.direct_delta_mush_bound
    ddm.set_direct_delta_mush(iterations=4, step=2.0)
    assert ddm.direct_delta_mush_bound
    ddm.update(0.0)
    np.testing.assert_allclose(ddm.positions, ddm.model.positions, atol=2e-5)  # the rest pose back
    for c in (lbs, ddm):
        pose = c.pose
        c.skeleton.set_euler(pose, "forearm_l", [110, 0, 0])
        c.pose = pose
        c.update(0.0)
    assert np.abs(ddm.positions - lbs.positions).max() > 1e-3
    for bad in ({"iterations": 0}, {"step": float("nan")}, {"prune": 0.7}):
        with pytest.raises(deform.Error):
            ddm.set_direct_delta_mush(**bad)
    assert ddm.direct_delta_mush_bound  # the binding in place kept
    ddm.clear_direct_delta_mush()
    assert not ddm.direct_delta_mush_bound
    ddm.update(0.0)
    np.testing.assert_array_equal(ddm.positions, lbs.positions)  # off: LBS to the bit
    # Without lattices the character's points are the job's on the same pose's palette.
    model = deform.Character.builtin().model
    bare = deform.Character(model)
    bare.set_direct_delta_mush()
    pose = bare.pose
    bare.skeleton.set_euler(pose, "forearm_l", [110, 0, 0])
    bare.pose = pose
    bare.update(0.0)
    _, palette = deform.forward_kinematics(bare.skeleton, bare.pose)
    np.testing.assert_allclose(bare.positions, deform.DirectDeltaMush(model).skin(palette), atol=1e-5)


def test_levels_of_detail_skin_with_fewer_bones_and_switch_on_request():
    hero = deform.Character.builtin()
    walk = [c for c in deform.builtin_clips(hero.model) if c.name == "walk"][0]
    poses = []
    for k in range(12):
        pose = hero.skeleton.bind_pose()
        walk.sample(walk.duration * k / 12, pose)
        poses.append(pose)
    hero.set_levels([14, 8], poses=poses, keep=["hips"], blend_frames=0)
    assert hero.level_count == 3 and hero.level == 0
    assert hero.level_cost(1)["bones"] == 14 and hero.level_cost(2)["bones"] == 8
    assert hero.level_cost(2)["influences"] < hero.level_cost(0)["influences"]
    pose = hero.skeleton.bind_pose()
    walk.sample(0.4, pose)
    shown = []
    for level in range(3):
        hero.set_level(level)
        hero.set_pose(pose)
        hero.update(0.0)
        shown.append(hero.positions.copy())
    height = np.ptp(shown[0][:, 1])
    # 14 bones judged on the walk skin its pose as all 33 do; 8 cannot (the knees).
    assert np.abs(shown[1] - shown[0]).max() < 1e-5 * height
    assert np.abs(shown[2] - shown[0]).max() > 0.01 * height
    with pytest.raises(deform.Error):
        hero.set_level(3)
    with pytest.raises(deform.Error):
        hero.set_levels([14, 20])  # more bones than the level before
    assert deform.pick_level([0.5, 0.2], deform.screen_height(1.8, 30.0, 1.0)) == 2


def test_a_level_deforms_only_its_points():
    full, mesh = deform.Character.builtin(), deform.Character.builtin()
    count = len(full.positions)
    even = list(range(0, count, 2))
    full.set_levels([14], deformers=[True, False])
    mesh.set_levels([14], deformers=[True, False], points=[[], even])
    assert mesh.level_cost(1)["points"] == len(even)
    for c in (full, mesh):
        c.set_level(1)
        c.update(0.0)  # the switch's update deforms the outgoing level 0 too
    before = mesh.positions.copy()
    pose = full.skeleton.bind_pose()
    walk = [c for c in deform.builtin_clips(full.model) if c.name == "walk"][0]
    walk.sample(0.4, pose)
    for c in (full, mesh):
        c.set_pose(pose)
        c.update(0.0)
    np.testing.assert_array_equal(mesh.positions[even], full.positions[even])
    np.testing.assert_array_equal(mesh.positions[1::2], before[1::2])  # not the level's: untouched
    assert np.abs(full.positions[1::2] - before[1::2]).max() > 1e-3
    mesh.set_levels([14], points=[[], even])  # deformers on with a subset: the spring chains alone
    with pytest.raises(deform.Error):
        mesh.set_levels([14], deformers=[True, False], points=[[], [len(full.positions)]])  # out of range
    with pytest.raises(deform.Error):
        mesh.set_levels([14], deformers=[True, False], points=[[]])  # not one per level


@pytest.mark.skipif(not deform.has_simplify, reason="needs deform::simplify (meshoptimizer)")
def test_simplified_meshes_as_levels():
    hero = deform.Character.builtin()
    model = hero.model
    levels = deform.simplify_levels(model, [0.25, 0.1])
    assert [len(lv["triangles"]) for lv in levels] == [1424, 594]
    near, far = levels
    assert len(far["points"]) < len(near["points"]) < model.point_count
    np.testing.assert_array_equal(near["points"][: len(far["points"])], far["points"])  # nested: the coarser first
    for level in levels:
        assert np.isin(level["triangles"], level["points"]).all()  # every corner a point of its level
        assert 0 < level["error"] < 0.2
    assert near["error"] <= far["error"]
    for level in levels:  # the same triangles over render vertices, for drawing with uvs and normals()
        np.testing.assert_array_equal(model.vertex_points[level["vertex_triangles"]], level["triangles"])
    hero.set_levels([20, 12], deformers=[True, True, False], points=[[], near["points"], far["points"]])
    assert [hero.level_cost(level)["points"] for level in range(3)] == [model.point_count, 714, 299]
    with pytest.raises(deform.Error):
        deform.simplify_levels(model, [0.1, 0.25])  # more triangles than the level before
