#!/usr/bin/env python3
"""`deform skin --blend` end to end: a clip of weight 1 (alone, or beside clips of weight 0) is `--clip` itself,
weights scaled together give the same points, an even blend of two clips lies between them, the summary lists the
blend, and exit 2 naming the bad item (nothing written) on a malformed --blend. With the importer, the same for an
imported character's clips (Testwuson.X from Debian's assimp-testmodels) and `deform info` listing its clips.
Usage: blend_cli_test.py DEFORM WORK_DIR [ASSIMP_MODELS]"""
import json, math, os, shutil, subprocess, sys

deform, work = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
models = sys.argv[3] if len(sys.argv) > 3 else ""
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


checks = 0


def check(condition, message):
    global checks
    checks += 1
    if not condition:
        failures.append(message)
    return condition


def run(*args):
    p = subprocess.run([deform, *args], capture_output=True, text=True, timeout=300, cwd=work)
    return p.returncode, p.stdout, p.stderr


def skin(model, *args):
    """Skins `model` (a list of arguments) with `args`; the points written, and the summary."""
    out = f"out{len(os.listdir(work))}.obj"
    rc, stdout, stderr = run("skin", *model, *args, "--out", out)
    if not check(rc == 0, f"skin {' '.join(model + list(args))}: exit {rc}: {stderr}"):
        return None, None
    with open(os.path.join(work, out)) as f:
        points = [tuple(map(float, line.split()[1:4])) for line in f if line.startswith("v ")]
    return points, json.loads(stdout)


def worst(a, b):
    return max(math.dist(p, q) for p, q in zip(a, b))


def blend_checks(name, model, first, second, time):
    a, _ = skin(model, "--clip", first, "--time", time)
    b, _ = skin(model, "--clip", second, "--time", time)
    alone, summary = skin(model, "--blend", f"{first}:1", "--time", time)
    if not (a and b and alone):
        return
    check(worst(alone, a) < 1e-6, f"{name}: --blend {first}:1 differs from --clip {first} by {worst(alone, a)}")
    check(summary.get("blend") == [{"clip": first, "weight": 1.0}], f"{name}: summary blend {summary.get('blend')}")
    zero, _ = skin(model, "--blend", f"{first}:1,{second}:0", "--time", time)
    check(zero and worst(zero, a) < 1e-6, f"{name}: a clip of weight 0 changed the pose")
    half, _ = skin(model, "--blend", f"{first}:0.5,{second}:0.5", "--time", time)
    scaled, _ = skin(model, "--blend", f"{first}:3,{second}:3", "--time", time)
    if half and scaled:
        check(worst(half, scaled) < 1e-5, f"{name}: weights scaled together moved a point by {worst(half, scaled)}")
        # Between the two: no point of the even blend is farther from either clip than the clips are apart
        # (plus a little: the blend is of rotations, not of points).
        apart = worst(a, b)
        check(apart > 0, f"{name}: {first} and {second} give the same points at {time}")
        check(worst(half, a) < apart and worst(half, b) < apart, f"{name}: the even blend is not between the clips")
        check(worst(half, a) > 0.1 * apart, f"{name}: the even blend is too near {first}")


# --- the built-in character's clips ---
blend_checks("builtin", ["--builtin"], "walk", "run", "0.3")
blend_checks("builtin", ["--builtin"], "idle", "wave", "1.25")

# --- bad --blend items: exit 2, the message names the item, nothing written ---
for value, expected in (("walk:-1", "walk:-1"), ("walk", "'walk'"), ("walk:abc", "walk:abc"),
                        ("walk:1,,run:1", "''"), ("walk:1,nope:1", "nope"), (":1", "':1'"),
                        ("walk:nan", "walk:nan"), ("walk:1e9", "walk:1e9")):
    rc, stdout, stderr = run("skin", "--builtin", "--blend", value, "--time", "0", "--out", "bad.obj")
    check(rc == 2, f"--blend {value}: exit {rc}, not 2")
    check(expected in stderr, f"--blend {value}: message does not name {expected}: {stderr.strip()}")
    check(not os.path.exists(os.path.join(work, "bad.obj")), f"--blend {value}: wrote the output")
for args, expected in ((["--blend", "walk:1"], "--time"),
                       (["--blend", "walk:1", "--clip", "walk", "--time", "0"], "--blend"),
                       (["--blend", "walk:1", "--pose", "p.json", "--time", "0"], "--blend")):
    rc, stdout, stderr = run("skin", "--builtin", *args, "--out", "bad.obj")
    check(rc == 2 and expected in stderr, f"{args}: exit {rc}, message {stderr.strip()}")
# Native files carry no clips.
samples = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "samples", "data")
rc, stdout, stderr = run("skin", os.path.join(samples, "builtin.obj"), "--skeleton", os.path.join(samples, "builtin.sk"),
                         "--weights", os.path.join(samples, "builtin.skw"), "--blend", "walk:1", "--time", "0",
                         "--out", "bad.obj")
check(rc == 2 and "--blend needs" in stderr, f"native files: exit {rc}, {stderr.strip()}")

# --- an imported character ---
wuson = os.path.join(models, "X", "Testwuson.X") if models else ""
if wuson and os.path.exists(wuson):
    rc, stdout, stderr = run("info", wuson)
    if check(rc == 0, f"info {wuson}: exit {rc}: {stderr}"):
        clips = {c["name"]: c for c in json.loads(stdout)["clips"]}
        check({"Wuson_Run", "Wuson_Walk"} <= set(clips), f"info clips: {sorted(clips)}")
        for c in clips.values():
            check(c["duration"] >= 0 and isinstance(c["interpolation"], list), f"info clip {c}")
        check(clips["Wuson_Run"]["duration"] > 0 and clips["Wuson_Run"]["interpolation"], f"info {clips['Wuson_Run']}")
    blend_checks("Testwuson.X", [wuson], "Wuson_Run", "Wuson_Walk", "0.37")
else:
    print("skipped the imported character (no importer, or Debian's assimp-testmodels missing)")

for f in failures:
    print("FAIL:", f)
print(f"{checks} checks, {len(failures)} failed")
sys.exit(1 if failures else 0)
