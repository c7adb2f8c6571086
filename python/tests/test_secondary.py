"""Secondary motion from Python: a walk that jiggles the arm the same at any frame rate, spring chains, and a chain's
rest angle under gravity against a NumPy reference."""
import numpy as np
import pytest

import deform

WALK_SECONDS = 1.0


def walk(hz, lead=True, inertia=1.0, each=None):
    """The left fingers over a walk, stepped at `hz`, at every 1/15 s (the wrist stays on the forearm, whose lattice
    keeps its far face on the bone: the hand lattice is what lags). `inertia` scales every lattice's tuned inertia;
    `each`, a list of inertias, sets each lattice's own instead."""
    model = deform.builtin_character()
    hero = deform.Character(model, deform.builtin_rig(model))
    if each is None:
        hero.set_lattice_motion(inertia)
    else:
        for lattice, value in enumerate(each):
            hero.set_lattice_motion(value, lattice=lattice)
    clip = [c for c in deform.builtin_clips(model) if c.name == "walk"][0]
    bind = model.skeleton.bind_pose()
    pose, later = bind, bind
    path, steps = [], int(round(WALK_SECONDS * hz))
    for n in range(steps + 1):
        t = n / hz
        pose = model.skeleton.bind_pose()
        clip.sample(t, pose)
        if lead:
            later = model.skeleton.bind_pose()
            clip.sample(t + 1e-3, later)
            hero.set_pose(pose, later, 1e-3)
        else:
            hero.set_pose(pose)
        hero.update(0.0 if n == 0 else 1.0 / hz)
        if n > 0 and n % int(round(hz / 15)) == 0:
            path.append(hero.bone_position("fingers1_l"))
    return np.array(path)


def test_the_walk_jiggles_the_same_at_30_and_120_hz():
    coarse, fine = walk(30), walk(120)
    travel = np.ptp(fine, axis=0).max()
    assert np.abs(coarse - fine).max() < 0.005 * travel
    rigid = walk(120, inertia=0.0)
    assert np.abs(rigid - fine).max() > 0.02  # the jiggle is there: the fingers lag the rigid walk by centimetres


def test_the_inertia_for_every_lattice_scales_each_parts_tuned_inertia():
    # The built-in rig's upper arm, forearm and hand (docs/elasticity.md, "Tuned per part"): 1 is their tuned inertia,
    # 0.5 half of it; one lattice's inertia is its own.
    assert np.array_equal(walk(60), walk(60, each=[0.3, 0.3, 0.2]))
    assert np.array_equal(walk(60, inertia=0.5), walk(60, each=[0.15, 0.15, 0.1]))
    assert not np.array_equal(walk(60), walk(60, each=[1.0, 1.0, 1.0]))


def test_without_a_lead_the_motion_between_frames_is_linear_and_frame_rates_part_more():
    with_lead = np.abs(walk(30) - walk(120)).max()
    without = np.abs(walk(30, lead=False) - walk(120, lead=False)).max()
    assert without > with_lead


def test_a_spring_chain_settles_where_gravity_and_its_spring_balance():
    # One link (the left hand's last finger bone, horizontal in the T-pose) under gravity: its tail settles at the
    # angle θ below the bone where ω²·L·sin θ = g·cos θ, the tangential balance of the spring toward the rest and gravity.
    model = deform.builtin_character()
    rig = deform.builtin_rig(model)
    rig.add_spring_chain(model, "finger", ["fingers2_l"], frequency=2.0, damping_ratio=0.7, gravity=(0, -9.81, 0))
    assert rig.spring_chain_names == ["ponytail", "finger"]  # the built-in rig's ponytail comes first
    hero = deform.Character(model, rig)
    assert hero.spring_chain_count == 2
    for _ in range(600):
        hero.update(1 / 60)
    assert hero.spring_points(0).shape == (5, 3)  # the ponytail: its root and four tails
    points = hero.spring_points(1)
    assert points.shape == (2, 3) and not points.flags.writeable
    bone = points[1] - points[0]
    length = np.linalg.norm(bone)
    omega = 2 * np.pi * 2.0
    expected = np.arctan(9.81 / (omega**2 * length))
    assert np.arcsin(-bone[1] / length) == pytest.approx(expected, rel=0.01)


def test_bad_secondary_motion_is_refused():
    model = deform.builtin_character()
    hero = deform.Character(model, deform.builtin_rig(model))
    with pytest.raises(deform.Error):
        hero.set_lattice_motion(2.0)
    with pytest.raises(deform.Error):
        hero.set_lattice_motion(0.5, lattice=99)
    with pytest.raises(deform.Error):
        hero.set_pose(model.skeleton.bind_pose(), model.skeleton.bind_pose(), 0.0)
    rig = deform.builtin_rig(model)
    with pytest.raises(deform.Error):
        rig.add_spring_chain(model, "x", ["neck"], frequency=0.0)
    assert hero.spring_chain_count == 1  # the ponytail
    with pytest.raises(deform.Error):
        hero.spring_points(1)
