"""The Character's morph weights: count, names, get and set by index and by name, from a clip, and what update() makes
of them (rest + w·delta on a model with one bone at rest)."""
import pathlib

import numpy as np
import pytest

import deform

CUBE = pathlib.Path("/usr/share/assimp/models/glTF2/glTF-Sample-Models/AnimatedMorphCube-glTF/AnimatedMorphCube.gltf")


def test_a_character_without_targets_has_no_weights():
    hero = deform.Character.builtin()
    assert hero.morph_target_count == 0
    assert hero.morph_target_names == []
    assert hero.morph_weights.shape == (0,)
    with pytest.raises(deform.Error):
        hero.set_morph_weight(0, 1.0)
    with pytest.raises(deform.Error):
        hero.set_morph_weight("smile", 1.0)
    with pytest.raises(deform.Error):
        hero.morph_weights = [1.0]


@pytest.mark.skipif(not deform.has_import or not CUBE.exists(), reason="needs deform::import and assimp-testmodels")
def test_morph_weights_by_index_name_and_clip():
    imported = deform.import_model(str(CUBE))
    cube = deform.Character(imported["model"])
    assert cube.morph_target_count == 2
    assert cube.morph_target_names == ["target0", "target1"]
    np.testing.assert_array_equal(cube.morph_weights, [0.0, 0.0])  # the file's defaults
    cube.update(0.0)
    rest = cube.positions.copy()

    cube.set_morph_weight("target0", 1.0)
    assert cube.morph_weight(0) == 1.0 and cube.morph_weight("target0") == 1.0
    cube.update(0.0)
    full = cube.positions.copy()
    moved = np.linalg.norm(full - rest, axis=1)
    assert moved.max() > 0.1 and (moved == 0).any()  # the target moves some points, not all

    # Linear in the weight: half the weight, half the displacement (one bone at rest: skinning is the identity).
    cube.set_morph_weight(0, 0.5)
    cube.update(0.0)
    np.testing.assert_allclose(cube.positions - rest, 0.5 * (full - rest), atol=1e-6)

    cube.morph_weights = [0.0, 1.0]
    np.testing.assert_array_equal(cube.morph_weights, [0.0, 1.0])
    for bad in (lambda: cube.set_morph_weight(2, 1.0), lambda: cube.set_morph_weight("nose", 1.0),
                lambda: cube.set_morph_weight(0, float("nan")), lambda: setattr(cube, "morph_weights", [1.0]),
                lambda: cube.morph_weight(-1)):
        with pytest.raises(deform.Error):
            bad()
    np.testing.assert_array_equal(cube.morph_weights, [0.0, 1.0])  # refusals change nothing

    # From the clip: its animated weights at a time; reset brings the defaults back.
    clip = imported["clips"][0]
    cube.reset_morph_weights()
    cube.set_morph_weights_from_clip(clip, 1.0)
    assert cube.morph_weights[0] > 0.1
    cube.reset_morph_weights()
    np.testing.assert_array_equal(cube.morph_weights, [0.0, 0.0])
    cube.update(0.0)
    np.testing.assert_array_equal(cube.positions, rest)
