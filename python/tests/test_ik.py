"""IK: CCD, FABRIK and two-bone reach what a pose can reach, with the settings that exist."""
import numpy as np
import pytest

import deform


@pytest.fixture
def skeleton(builtin_model):
    return builtin_model.skeleton


def reachable_target(skeleton, root, effector):
    pose = skeleton.bind_pose()
    skeleton.set_euler(pose, "upperarm_l", [10, 20, -30])
    skeleton.set_euler(pose, "forearm_l", [60, 0, 0])  # the elbow's hinge is X
    return np.array(deform.effector_position(skeleton, pose, root, effector), np.float32)


@pytest.mark.parametrize("method", ["ccd", "fabrik"])
def test_iterative_solvers_reach_a_reachable_target(skeleton, method):
    target = reachable_target(skeleton, "clavicle_l", "hand_l")
    pose = skeleton.bind_pose()
    start = np.array(deform.effector_position(skeleton, pose, "clavicle_l", "hand_l"))
    assert np.linalg.norm(start - target) > 0.1
    result = deform.solve_ik(skeleton, pose, "clavicle_l", "hand_l", target, method=method, tolerance=1e-3)
    assert result.reached and result.distance <= 1e-3
    reached = np.array(deform.effector_position(skeleton, pose, "clavicle_l", "hand_l"))
    assert np.linalg.norm(reached - target) == pytest.approx(result.distance, abs=1e-4)
    for bone in ("clavicle_l", "upperarm_l", "forearm_l"):
        assert skeleton.within_limits(pose, bone)


def test_two_bone_reaches_and_bends_toward_the_pole(skeleton):
    target = reachable_target(skeleton, "upperarm_l", "hand_l")
    elbows = []
    for pole in ([0.5, 1.4, -1.0], [0.5, 1.4, 1.0]):
        pose = skeleton.bind_pose()
        # limits=False: the closed form's bend plane is the pole's; the elbow's limits would clamp it out of it.
        result = deform.solve_ik(skeleton, pose, "upperarm_l", "hand_l", target, method="two_bone", pole=pole,
                                 limits=False)
        assert result.reached and result.iterations == 1
        elbows.append(np.array(deform.effector_position(skeleton, pose, "upperarm_l", "forearm_l")))
    assert elbows[0][2] < elbows[1][2]  # each elbow bends to its side


def test_weight_zero_leaves_the_pose(skeleton):
    target = reachable_target(skeleton, "clavicle_l", "hand_l")
    pose = skeleton.bind_pose()
    before = pose.rotations.copy()
    deform.solve_ik(skeleton, pose, "clavicle_l", "hand_l", target, weight=0.0)
    np.testing.assert_allclose(pose.rotations, before, atol=1e-6)


def test_limits_can_be_lifted(skeleton):
    # Low and behind: out of reach within the arm's limits, nearer with free joints.
    target = np.array([0.3, 0.8, -0.3], np.float32)
    limited, free = skeleton.bind_pose(), skeleton.bind_pose()
    a = deform.solve_ik(skeleton, limited, "clavicle_l", "hand_l", target)
    b = deform.solve_ik(skeleton, free, "clavicle_l", "hand_l", target, limits=False)
    assert not a.reached and b.distance < 0.7 * a.distance
    assert all(skeleton.within_limits(limited, bone) for bone in ("clavicle_l", "upperarm_l", "forearm_l"))


def test_bad_settings_raise(skeleton):
    pose = skeleton.bind_pose()
    with pytest.raises(deform.Error):
        deform.solve_ik(skeleton, pose, "clavicle_l", "hand_l", [0, 1, 0], method="magic")
    with pytest.raises(deform.Error) as info:
        deform.solve_ik(skeleton, pose, "clavicle_l", "hand_l", [0, 1, 0], weight=2.0)
    assert info.value.kind == "status"
    with pytest.raises(deform.Error):
        deform.solve_ik(skeleton, pose, "clavicle_l", "hand_l", [0, 1, 0], method="two_bone")  # three joints
