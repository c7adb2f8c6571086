"""Loading native files, the built-in character, imports, automatic weights and export."""
import pathlib

import numpy as np
import pytest

import deform

WUSON = pathlib.Path("/usr/share/assimp/models/X/Testwuson.X")  # Debian's assimp-testmodels


def test_native_files_hold_the_builtin_character(native_paths, builtin_model):
    model = deform.load_model(*native_paths)
    assert model.point_count == builtin_model.point_count == 2850
    assert model.skeleton.names == builtin_model.skeleton.names
    np.testing.assert_allclose(model.positions, builtin_model.positions, atol=1e-6)
    np.testing.assert_array_equal(model.bone_indices, builtin_model.bone_indices)


def test_save_and_reload(tmp_path, model):
    paths = [str(tmp_path / f"m.{ext}") for ext in ("obj", "sk", "skw")]
    model.save(*paths)
    again = deform.load_model(*paths)
    np.testing.assert_array_equal(again.positions, model.positions)
    np.testing.assert_array_equal(again.triangles, model.triangles)
    np.testing.assert_array_equal(again.skeleton.parents, model.skeleton.parents)
    np.testing.assert_allclose(again.bone_weights, model.bone_weights, atol=1e-6)


def test_save_obj_writes_deformed_positions(tmp_path, native_paths):
    hero = deform.Character.builtin()
    hero.reach("hand_l", [1.6, 1.5, 0.3])
    for _ in range(30):
        hero.update(1 / 60)
    obj = str(tmp_path / "posed.obj")
    model = hero.model
    deform.save_obj(obj, model, hero.positions)
    again = deform.load_model(obj, native_paths[1], native_paths[2])
    np.testing.assert_array_equal(again.positions, hero.positions)


def test_automatic_weights_are_the_builtin_ones(builtin_model):
    bones, weights = deform.compute_automatic_weights(builtin_model, builtin_model.skeleton)
    assert bones.shape == weights.shape == (builtin_model.point_count, 4)
    np.testing.assert_allclose(weights.sum(axis=1), 1, atol=1e-5)
    np.testing.assert_array_equal(bones, builtin_model.bone_indices)
    np.testing.assert_allclose(weights, builtin_model.bone_weights, atol=1e-6)
    only_points = deform.compute_automatic_weights(builtin_model.positions, builtin_model.skeleton, max_influences=2)
    assert np.all(only_points[1][:, 2:] == 0)


def test_set_weights_checks_the_size(model):
    bones, weights = deform.compute_automatic_weights(model, model.skeleton, falloff_power=8)
    model.set_weights(bones, weights)
    np.testing.assert_array_equal(model.bone_weights, weights)
    with pytest.raises(deform.Error):
        model.set_weights(bones[:10], weights[:10])


@pytest.mark.skipif(not deform.has_import or not WUSON.exists(), reason="needs deform::import and assimp-testmodels")
def test_import_and_export_native(tmp_path):
    imported = deform.import_model(str(WUSON))
    model = imported["model"]
    assert imported["rigged"] and model.point_count > 100 and len(model.skeleton) > 1
    assert [clip.name for clip in imported["clips"]] == ["Wuson_Run", "Wuson_Walk", "Wuson_Bind"]
    run = imported["clips"][0]
    assert run.duration > 0
    poses = []
    for time in (0.0, run.duration / 2):
        pose = model.skeleton.bind_pose()
        run.sample(time, pose)
        poses.append(pose.rotations.copy())
    assert not np.allclose(poses[0], poses[1], atol=1e-3)  # the clip moves
    _, palette = deform.forward_kinematics(model.skeleton, pose)
    posed = deform.skin(model.positions, model.bone_indices, model.bone_weights, palette)
    assert np.isfinite(posed).all() and np.abs(posed - model.positions).max() > 0
    files = deform.export_native(model, str(tmp_path))
    again = deform.load_model(files["obj"], files["sk"], files["skw"])
    assert again.point_count == model.point_count
    np.testing.assert_allclose(again.positions, model.positions, atol=1e-5)


@pytest.mark.skipif(not deform.has_import, reason="needs deform::import")
def test_import_error_names_the_file(tmp_path):
    bad = tmp_path / "broken.gltf"
    bad.write_text("{ not json")
    with pytest.raises(deform.Error) as info:
        deform.import_model(str(bad))
    assert str(bad) in str(info.value)


@pytest.mark.skipif(not deform.has_import or not WUSON.exists(), reason="needs deform::import and assimp-testmodels")
def test_a_saved_rig_names_its_imported_model(tmp_path):
    import json
    model = deform.import_model(str(WUSON))["model"]
    rig = deform.default_rig(model)
    path = tmp_path / "rigs" / "wuson.rig.json"
    path.parent.mkdir()
    rig.save(str(path), model, model_file=str(WUSON))
    written = json.loads(path.read_text())
    # Relative to the rig's folder, which is how `deform simulate RIG` finds it.
    assert (path.parent / written["model"]["file"]).resolve() == WUSON.resolve()
    assert deform.read_rig(str(path), model).lattice_names == rig.lattice_names
    rig.save(str(path), model)  # no model_file: the rig says what it knows, here nothing
    assert "model" not in json.loads(path.read_text())
def _secret_and_obj(tmp_path):
    """A secret beside the model's folder and an OBJ that names it as its MTL file."""
    (tmp_path / "private").mkdir()
    (tmp_path / "private" / "secret.mtl").write_text("SECRET-7e57\nnewmtl s\n")
    (tmp_path / "m").mkdir()
    obj = tmp_path / "m" / "body.obj"
    obj.write_text("mtllib ../private/secret.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    return obj


def test_files_outside_the_model_folder_are_refused(tmp_path, native_paths):
    obj = _secret_and_obj(tmp_path)
    with pytest.raises(deform.Error) as info:
        deform.load_model(str(obj), native_paths[1], native_paths[2])
    assert info.value.kind == "input" and "mtllib" in str(info.value) and "SECRET" not in str(info.value)
    # Allowed on purpose, the OBJ is read; the built-in skeleton's weights then do not fit its 3 points.
    with pytest.raises(deform.Error) as info:
        deform.load_model(str(obj), native_paths[1], native_paths[2], allow_outside=[str(tmp_path / "private")])
    assert "mtllib" not in str(info.value)


@pytest.mark.skipif(not deform.has_import, reason="needs deform::import")
def test_import_refuses_a_buffer_outside_the_model_folder(tmp_path):
    (tmp_path / "private").mkdir()
    (tmp_path / "private" / "secret.bin").write_bytes(b"SECRET-7e57" + bytes(25))
    (tmp_path / "m").mkdir()
    model = tmp_path / "m" / "x.gltf"
    model.write_text('{"asset": {"version": "2.0"}, "buffers": [{"uri": "..%2fprivate/secret.bin", "byteLength": 36}],'
                     ' "bufferViews": [{"buffer": 0, "byteLength": 36}], "accessors": [{"bufferView": 0,'
                     ' "componentType": 5126, "count": 3, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]}],'
                     ' "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}], "nodes": [{"mesh": 0}],'
                     ' "scenes": [{"nodes": [0]}], "scene": 0}')
    with pytest.raises(deform.Error) as info:
        deform.import_model(str(model))
    assert "buffers[0].uri" in str(info.value) and "36" not in str(info.value).replace(str(tmp_path), "")
    imported = deform.import_model(str(model), allow_outside=[str(tmp_path / "private")])
    assert imported["model"].point_count > 0
