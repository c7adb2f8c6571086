#!/usr/bin/env python3
"""Compares one target's scene (tests/engine/scene.cpp's output) with x86-64's.

    compare_scene.py REFERENCE.txt SCENE.txt [--positions METRES] [--normals TOLERANCE]

Both files must hold the same frames with the same counts of positions and normals. Prints, per frame and over all,
the largest difference of any coordinate of a position (metres) and of any component of a normal (unit vectors);
exits 1 when one exceeds its tolerance or the files do not match in shape, 0 otherwise.
"""
import argparse
import os
import sys


def read_scene(path):
    """{frame: (positions, normals)}, each a list of (x, y, z); the counts each frame line gives are checked."""
    frames, counts, current = {}, {}, None
    with open(path, encoding="ascii") as f:
        for number, line in enumerate(f, 1):
            words = line.split()
            if not words or words[0].startswith("#"):
                continue
            if words[0] == "frame" and len(words) == 6:
                current = frames.setdefault(int(words[1]), ([], []))
                counts[int(words[1])] = (int(words[3]), int(words[5]))
            elif words[0] in ("p", "n") and current is not None and len(words) == 4:
                current[0 if words[0] == "p" else 1].append(tuple(float(w) for w in words[1:]))
            else:
                raise ValueError(f"{path}:{number}: not a scene line: {line.strip()[:60]}")
    for frame, (positions, normals) in frames.items():
        if (len(positions), len(normals)) != counts[frame] or not positions:
            raise ValueError(f"{path}: frame {frame} holds {len(positions)} positions and {len(normals)} normals, "
                             f"not the {counts[frame][0]} and {counts[frame][1]} it announces")
    if not frames:
        raise ValueError(f"{path}: no frames")
    return frames


def largest(a, b):
    return max((abs(x - y) for u, v in zip(a, b) for x, y in zip(u, v)), default=0.0)


def compare(reference, scene, position_tolerance, normal_tolerance):
    """(report lines, failures)."""
    lines, failures = [], []
    if sorted(reference) != sorted(scene):
        return lines, [f"frames {sorted(scene)} where x86-64 has {sorted(reference)}"]
    worst_p = worst_n = 0.0
    for frame in sorted(reference):
        (rp, rn), (sp, sn) = reference[frame], scene[frame]
        if len(rp) != len(sp) or len(rn) != len(sn):
            failures.append(f"frame {frame}: {len(sp)} positions and {len(sn)} normals where x86-64 has "
                            f"{len(rp)} and {len(rn)}")
            continue
        dp, dn = largest(rp, sp), largest(rn, sn)
        worst_p, worst_n = max(worst_p, dp), max(worst_n, dn)
        lines.append(f"frame {frame}: positions {dp:.3g} m, normals {dn:.3g}")
        if not dp <= position_tolerance:
            failures.append(f"frame {frame}: a position differs by {dp:.3g} m (tolerance {position_tolerance:g})")
        if not dn <= normal_tolerance:
            failures.append(f"frame {frame}: a normal differs by {dn:.3g} (tolerance {normal_tolerance:g})")
    lines.append(f"largest difference from x86-64: positions {worst_p:.3g} m, normals {worst_n:.3g}")
    return lines, failures


def self_check():
    """The comparison must be able to fail: a moved point, a turned normal, a missing frame."""
    a = {1: ([(0.0, 0.0, 0.0)], [(0.0, 1.0, 0.0)])}
    b = {1: ([(0.0, 2e-4, 0.0)], [(0.0, 1.0, 0.0)])}
    assert compare(a, b, 1e-4, 1e-3)[1], "a position 2e-4 m off passed"
    assert not compare(a, a, 1e-4, 1e-3)[1]
    c = {1: ([(0.0, 0.0, 0.0)], [(0.0, 1.0, 2e-3)])}
    assert compare(a, c, 1e-4, 1e-3)[1], "a normal 2e-3 off passed"
    assert compare(a, {2: a[1]}, 1e-4, 1e-3)[1], "a different frame passed"


def main():
    self_check()
    parser = argparse.ArgumentParser()
    parser.add_argument("reference")
    parser.add_argument("scene")
    parser.add_argument("--positions", type=float, default=1e-4)
    parser.add_argument("--normals", type=float, default=1e-4)
    args = parser.parse_args()
    if not os.path.isfile(args.reference):
        print(f"compare_scene: {args.reference}: no such file: x86-64's scene is written by a native build's "
              "engine_scene_native test (ctest --test-dir build -R engine_scene_native), scripts/test's GCC pass")
        return 1
    try:
        reference, scene = read_scene(args.reference), read_scene(args.scene)
    except (OSError, ValueError) as e:
        print(f"compare_scene: {e}")
        return 1
    lines, failures = compare(reference, scene, args.positions, args.normals)
    for line in lines + failures:
        print(line)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
