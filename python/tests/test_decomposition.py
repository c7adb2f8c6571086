"""Baking bones from Python: a reach-stretch-release recorded, decomposed into extra bones, written as glTF."""
import numpy as np
import pytest

import deform


def record_reach(hero, seconds=2.0, fps=15, dt=1 / 60):
    """The built-in character reaching far with its left hand, released after one second, a frame every 1/fps s."""
    frames = deform.DecompositionFrames()
    hero.reach("hand_l", np.array([1.6, 1.5, 0.3], np.float32))
    hero.update(0.0)
    frames.add(0.0, hero)
    steps = int(round(1 / (fps * dt)))
    for k in range(1, int(seconds * fps) + 1):
        if k == fps + 1:
            hero.release()
        for _ in range(steps):
            hero.update(dt)
        frames.add(k / fps, hero)
    return frames


def test_a_reach_bakes_into_a_few_bones_within_the_targets(tmp_path):
    hero = deform.Character.builtin()
    frames = record_reach(hero)
    assert len(frames) == 31
    fit = deform.decompose_skinning(hero.model, frames, max_bones=12, seeds=deform.decomposition_seeds(hero))
    assert 0 < fit.extra_bones <= 12
    assert fit.skeleton.bone_count == hero.model.skeleton.bone_count + fit.extra_bones
    assert len(fit.moved_points) > 0 and fit.moved_points.dtype == np.uint32
    assert fit.rms_error <= 0.005 and fit.max_error <= 0.02
    assert fit.frame_max_error.shape == (31,) and fit.frame_max_error.max() == pytest.approx(fit.max_error)
    # Without extra bones the stretch is what is left: the bones take most of it away.
    body = deform.decompose_skinning(hero.model, frames, max_bones=0)
    assert body.extra_bones == 0 and body.max_error > 5 * fit.max_error
    assert [clip.name for clip in fit.clips] == ["bake"]
    written = deform.write_gltf(str(tmp_path / "reach.glb"), fit.model(hero.model), fit.clips)
    assert written["bytes"] == (tmp_path / "reach.glb").stat().st_size and written["bin"] is None
    if deform.has_import:
        back = deform.import_model(str(tmp_path / "reach.glb"))
        assert back["model"].skeleton.bone_count == fit.skeleton.bone_count
        assert [clip.name for clip in back["clips"]] == ["bake"]


def test_two_clips_share_one_set_of_bones():
    first, second = record_reach(deform.Character.builtin(), seconds=1.0), record_reach(deform.Character.builtin())
    first.name, second.name = "short", "long"
    fit = deform.decompose_skinning(deform.Character.builtin().model, [first, second], max_bones=8)
    assert [clip.name for clip in fit.clips] == ["short", "long"]
    assert len(fit.frame_max_error) == len(first) + len(second) and fit.max_error <= 0.02


def test_bad_options_raise():
    hero = deform.Character.builtin()
    frames = record_reach(hero, seconds=0.2)
    with pytest.raises(deform.Error, match="influences"):
        deform.decompose_skinning(hero.model, frames, influences=9)
    with pytest.raises(deform.Error, match="frames"):
        deform.decompose_skinning(hero.model, deform.DecompositionFrames())
    with pytest.raises(deform.Error, match="clips"):
        deform.decompose_skinning(hero.model, [])
