"""The figure of docs/gltf-export.md, "Baking bones": how far a bones bake and a morph bake play from libdeform's own
motion, over time, between their frames as well as on them.

    PYTHONPATH=build/python python3 python/examples/bake_figures.py [--out docs/images]

Records the built-in character 60 times a second through two motions, the reach-stretch-release (the left hand to
(1.6, 1.5, 0.3), released after 1 s) and the walk with the tuned jiggle, and bakes every other frame (30 Hz) both
ways: as bones (decompose_skinning, 24 extra bones, 4 influences), played as an engine plays a glTF clip (the keys
interpolated, forward kinematics, linear blend skinning), and as morph targets, which a viewer blends linearly
between two frames. The 60 Hz frames in between are the truth neither bake saw. Writes bake-error.png (the largest
distance over the mesh at each time, as a percentage of the bounding-box diagonal) and prints a table of the
largest and RMS distances on the baked frames and between them. Needs the deform module and matplotlib.
"""
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import deform  # noqa: E402

HZ = 60


def record(motion, seconds):
    """The character through `motion` at 60 Hz: every position, and every other frame for the bake."""
    hero = deform.Character.builtin()
    baked = deform.DecompositionFrames()
    truth = []
    step = motion(hero)
    for k in range(int(seconds * HZ) + 1):
        step(k / HZ)
        truth.append(np.array(hero.positions))
        if k % 2 == 0:
            baked.add(k / HZ, hero)
    return hero, baked, truth


def reach(hero):
    hero.reach("hand_l", np.array([1.6, 1.5, 0.3], np.float32))

    def step(t):
        if abs(t - 1.0) < 1e-9:
            hero.release()
        hero.update(0.0 if t == 0 else 1 / HZ)
    return step


def walk(hero):
    hero.set_lattice_motion(1.0)  # the tuned jiggle of every lattice
    clip = next(c for c in deform.builtin_clips(hero.model) if c.name == "walk")

    def step(t):
        now, later = hero.model.skeleton.bind_pose(), hero.model.skeleton.bind_pose()
        clip.sample(t, now)
        clip.sample(t + 1e-3, later)
        hero.set_pose(now, later, 1e-3)
        hero.update(0.0 if t == 0 else 1 / HZ)
    return step


def errors(name, motion, seconds):
    hero, baked, truth = record(motion, seconds)
    fit = deform.decompose_skinning(hero.model, baked, seeds=deform.decomposition_seeds(hero))
    model = fit.model(hero.model)
    rest = np.asarray(hero.model.positions)
    diagonal = np.linalg.norm(rest.max(axis=0) - rest.min(axis=0))
    bones, morphs = [], []
    for k, goal in enumerate(truth):
        pose = fit.skeleton.bind_pose()
        fit.clips[0].sample(k / HZ, pose)
        _, palette = deform.forward_kinematics(fit.skeleton, pose)
        played = deform.skin(model.positions, model.bone_indices, model.bone_weights, palette)
        blended = truth[k] if k % 2 == 0 else 0.5 * (truth[k - 1] + truth[k + 1]) if k + 1 < len(truth) else truth[k]
        bones.append(np.linalg.norm(played - goal, axis=1) / diagonal * 100)
        morphs.append(np.linalg.norm(blended - goal, axis=1) / diagonal * 100)
    return name, fit, np.array(bones), np.array(morphs)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default="docs/images", help="folder for bake-error.png")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cases = [errors("reach-stretch-release", reach, 3.0), errors("walk with the jiggle", walk, 2.0)]
    figure, axes = plt.subplots(1, 2, figsize=(11, 3.6), sharey=True)
    print("| motion | bake | largest on frames | largest between | RMS on frames | RMS between |")
    print("|---|---|---:|---:|---:|---:|")
    for ax, (name, fit, bones, morphs) in zip(axes, cases):
        times = np.arange(len(bones)) / HZ
        ax.plot(times, morphs.max(axis=1), color="tab:orange", lw=0.8, alpha=0.8, label="morph targets")
        ax.plot(times, bones.max(axis=1), color="tab:blue", lw=1.6, label=f"bones ({fit.extra_bones} extra)")
        ax.set_title(name)
        ax.set_xlabel("seconds")
        ax.set_yscale("symlog", linthresh=0.01)
        ax.grid(alpha=0.3)
        for label, e in (("bones", bones), ("morphs", morphs)):
            on, between = e[0::2], e[1::2]
            print(f"| {name} | {label} | {on.max():.3f}% | {between.max():.3f}% | "
                  f"{np.sqrt((on ** 2).mean()):.4f}% | {np.sqrt((between ** 2).mean()):.4f}% |")
    axes[0].set_ylabel("largest distance, % of the diagonal")
    axes[0].legend(loc="upper right")
    figure.suptitle("Baked at 30 Hz, played against the 60 Hz simulation", fontsize=10)
    figure.tight_layout()
    figure.savefig(out / "bake-error.png", dpi=110)


if __name__ == "__main__":
    main()
