#!/usr/bin/env python3
"""deform ik end to end: solves, output contract, the reported effector equals FK of the reported angles, exit codes.

usage: ik_cli_test.py DEFORM_EXE WORK_DIR
FK here is written independently of libdeform from docs/formats.md: L = T(t) · Rx · Ry · Rz, W = W_parent · L.
"""
import json, math, os, struct, subprocess, sys

exe, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []


def check(condition, what):
    if not condition:
        failures.append(what)
        print("FAIL:", what)


# --- a small arm: base -> shoulder -> elbow -> wrist -> hand, plus a sibling ---
FREE = ((-180, 180), (-180, 180), (-180, 180))
BONES = [  # name, parent, translation, rotation, limits ((min,max) per axis)
    ("base", -1, (0, 0, 0), (0, 0, 0), FREE),
    ("shoulder", 0, (0, 1, 0), (0, 0, 0), FREE),
    ("elbow", 1, (1, 0, 0), (0, 0, 0), ((-90, 90), (-150, 0), (-90, 90))),
    ("wrist", 2, (1, 0, 0), (0, 0, 0), FREE),
    ("hand", 3, (0.5, 0, 0), (0, 0, 0), FREE),
    ("head", 0, (0, 1.5, 0), (0, 0, 0), FREE),
]


def write_sk(path):
    data = b"SKEL" + struct.pack("<i", len(BONES))
    for i, (name, parent, t, r, lim) in enumerate(BONES):
        children = [j for j, b in enumerate(BONES) if b[1] == i]
        data += name.encode().ljust(80, b"\0") + struct.pack("<6f", *t, *r)
        data += struct.pack("<6f", lim[0][1], lim[0][0], lim[1][1], lim[1][0], lim[2][1], lim[2][0])
        data += struct.pack("<ii", parent, len(children)) + struct.pack("<%di" % len(children), *children)
    with open(path, "wb") as f:
        f.write(data)


def qmul(a, b):
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx, aw * bz + ax * by - ay * bx + az * bw)


def qrot(q, v):
    w, x, y, z = qmul(qmul(q, (0.0, *v)), (q[0], -q[1], -q[2], -q[3]))
    return (x, y, z)


def q_euler(e):
    h = [math.radians(a) / 2 for a in e]
    return qmul(qmul((math.cos(h[0]), math.sin(h[0]), 0, 0), (math.cos(h[1]), 0, math.sin(h[1]), 0)),
                (math.cos(h[2]), 0, 0, math.sin(h[2])))


def head_of(name, pose):
    """World head of a bone; pose: name -> {rotation, translation}, else bind values."""
    chain = []
    i = [b[0] for b in BONES].index(name)
    while i >= 0:
        chain.append(i)
        i = BONES[i][1]
    q, p = (1.0, 0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    for i in reversed(chain):
        name_i, _, t, r, _ = BONES[i]
        entry = pose.get(name_i, {})
        t = entry.get("translation", t)
        r = entry.get("rotation", r)
        p = tuple(a + b for a, b in zip(p, qrot(q, t)))
        q = qmul(q, q_euler(r))
    return p


def run(*args):
    proc = subprocess.run([exe, "ik", *args], capture_output=True, text=True, timeout=60)
    return proc.returncode, proc.stdout, proc.stderr


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


sk = os.path.join(work, "arm.sk")
write_sk(sk)
LENGTH = 2.5  # shoulder -> hand

for solver, root in (("ccd", "shoulder"), ("fabrik", "shoulder"), ("two-bone", "elbow")):
    target = (1.2, 1.9, 0.6) if root == "shoulder" else (1.4, 1.3, 0.2)
    code, out, err = run(sk, "--effector", "hand", "--target", ",".join(map(str, target)), "--root", root,
                         "--solver", solver)
    check(code == 0, f"{solver}: exit {code} ({err.strip()})")
    if code != 0:
        continue
    doc = json.loads(out)
    check(list(doc) == ["solver", "reached", "distance", "iterations", "effector", "bones"], f"{solver}: keys {list(doc)}")
    check(doc["solver"] == solver, f"{solver}: solver field")
    check(doc["reached"] is True, f"{solver}: reached {doc['reached']} distance {doc['distance']}")
    check(doc["distance"] <= 1e-3, f"{solver}: distance {doc['distance']}")
    check(dist(doc["effector"], target) <= 1e-3, f"{solver}: effector {doc['effector']} vs target {target}")
    check(abs(dist(doc["effector"], target) - doc["distance"]) <= 1e-5, f"{solver}: distance is |effector - target|")
    chain = ["shoulder", "elbow", "wrist", "hand"] if root == "shoulder" else ["elbow", "wrist", "hand"]
    check(list(doc["bones"]) == chain, f"{solver}: bones {list(doc['bones'])}")
    # Feed the printed bones back through an independent FK: the effector the tool reports.
    fk = head_of("hand", doc["bones"])
    check(dist(fk, doc["effector"]) <= 1e-4, f"{solver}: FK of printed bones {fk} vs effector {doc['effector']}")
    elbow = doc["bones"]["elbow"]["rotation"]
    check(-150 - 1e-3 <= elbow[1] <= 1e-3, f"{solver}: elbow y {elbow[1]} outside its limits")
    check(1 <= doc["iterations"] <= 100, f"{solver}: iterations {doc['iterations']}")

# Unreachable: not an error; the closest pose, the straight arm pointing at the target.
code, out, err = run(sk, "--effector", "hand", "--target", "10,1,0", "--root", "shoulder", "--max-iterations", "300")
check(code == 0, f"unreachable: exit {code} ({err.strip()})")
if code == 0:
    doc = json.loads(out)
    check(doc["reached"] is False, "unreachable: reached must be false")
    best = dist((10, 1, 0), (0, 1, 0)) - LENGTH
    check(abs(doc["distance"] - best) <= 1e-3, f"unreachable: distance {doc['distance']} vs {best}")
    check(dist(head_of("hand", doc["bones"]), doc["effector"]) <= 1e-4, "unreachable: FK of printed bones")

# --tolerance and --max-iterations are honoured.
code, out, _ = run(sk, "--effector", "hand", "--target", "0.3,2.2,1.4", "--max-iterations", "1", "--tolerance", "0")
check(code == 0 and json.loads(out)["iterations"] == 1, "--max-iterations 1 gives one iteration")

# Bad usage and invalid input: exit 2, message on stderr, nothing on stdout.
for args, what in (
    ((sk, "--effector", "nope", "--target", "1,1,1"), "unknown effector"),
    ((sk, "--effector", "hand", "--target", "1,1"), "target with two numbers"),
    ((sk, "--effector", "hand", "--target", "nan,0,0"), "non-finite target"),
    ((sk, "--effector", "hand", "--target", "1,inf,0"), "infinite target"),
    ((sk, "--target", "1,1,1"), "missing --effector"),
    ((sk, "--effector", "hand"), "missing --target"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--root", "head"), "root not an ancestor"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--solver", "two-bone", "--root", "shoulder"), "two-bone on 3 joints"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--solver", "magic"), "unknown solver"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--max-iterations", "0"), "zero iterations"),
    ((sk, "--effector", "hand", "--target", "1,1,1", "--tolerance", "-1"), "negative tolerance"),
    ((os.path.join(work, "missing.sk"), "--effector", "hand", "--target", "1,1,1"), "missing file"),
    (("--effector", "hand", "--target", "1,1,1"), "no skeleton"),
):
    code, out, err = run(*args)
    check(code == 2 and out == "" and err != "", f"{what}: exit {code}, stdout {out!r}")

# A truncated .sk is invalid input, not a crash.
with open(sk, "rb") as f:
    data = f.read()
bad = os.path.join(work, "truncated.sk")
with open(bad, "wb") as f:
    f.write(data[:100])
code, out, err = run(bad, "--effector", "hand", "--target", "1,1,1")
check(code == 2 and "truncated.sk" in err, f"truncated file: exit {code}, {err.strip()}")

# The built-in character.
code, out, err = run("--builtin", "--effector", "hand_l", "--root", "upperarm_l", "--target", "0.6,1.3,0.2")
check(code == 0, f"--builtin: exit {code} ({err.strip()})")
if code == 0:
    doc = json.loads(out)
    check(list(doc["bones"]) == ["upperarm_l", "forearm_l", "hand_l"], f"--builtin: bones {list(doc['bones'])}")
    check(doc["distance"] >= 0 and len(doc["effector"]) == 3, "--builtin: output")

# The contract end to end: limits wider than ±90° about y (so that the in-limit Euler triple is often not the
# canonical |y| <= 90° one) and narrow about x and z. Every printed angle is within its bone's limits, and
# `deform skin --pose` of the printed bones puts a vertex bound rigidly to the effector exactly at the printed effector.
import random
WIDE = [  # name, parent, translation, rotation, limits
    ("base", -1, (0, 0, 0), (0, 0, 0), FREE),
    ("j1", 0, (0, 1, 0), (0, 0, 0), ((-30, 30), (-120, 120), (-25, 25))),
    ("j2", 1, (1, 0, 0), (0, 0, 0), ((-20, 40), (-160, 150), (-30, 10))),
    ("j3", 2, (0.8, 0, 0.2), (0, 0, 0), ((-180, -150), (-120, 180), (-15, 15))),
    ("j4", 3, (0.6, 0.1, 0), (0, 0, 0), ((-10, 10), (-170, 170), (-10, 10))),
    ("tip", 4, (0.4, 0, 0), (0, 0, 0), FREE),
]
saved = BONES
BONES = WIDE
wide_sk = os.path.join(work, "wide.sk")
write_sk(wide_sk)
tip_bind = head_of("tip", {})
mesh = os.path.join(work, "tip.obj")
with open(mesh, "w") as f:
    f.write("v %r %r %r\nv 0 0 0\nv 0 1 0\nf 1 2 3\n" % tip_bind)
with open(os.path.join(work, "tip.skw"), "w") as f:
    f.write("skw 1\nvertices 3\n0 5 1\n1 0 1\n2 0 1\n")
rng = random.Random(1123)
limits_of = {b[0]: b[4] for b in WIDE}
beyond_90 = 0
for case in range(24):
    solver = ("ccd", "fabrik")[case % 2]
    # FK of random in-limit angles: reachable targets that need |y| > 90° somewhere.
    angles = {b[0]: {"rotation": [rng.uniform(lo, hi) for lo, hi in b[4]]} for b in WIDE[1:5]}
    target = head_of("tip", angles)
    code, out, err = run(wide_sk, "--effector", "tip", "--root", "j1", "--solver", solver,
                         "--target", ",".join("%.6f" % x for x in target))
    check(code == 0, f"wide {case}: exit {code} ({err.strip()})")
    if code != 0:
        continue
    doc = json.loads(out)
    for name, entry in doc["bones"].items():
        for axis, (value, (lo, hi)) in enumerate(zip(entry["rotation"], limits_of[name])):
            check(lo <= value <= hi, f"wide {case} {solver}: {name} axis {axis} = {value} outside [{lo}, {hi}]")
        beyond_90 += name != "tip" and abs(entry["rotation"][1]) > 90
    check(dist(head_of("tip", doc["bones"]), doc["effector"]) <= 1e-4, f"wide {case} {solver}: FK of printed bones")
    pose = os.path.join(work, "wide_pose.json")
    with open(pose, "w") as f:
        json.dump({"bones": doc["bones"]}, f)
    skinned = os.path.join(work, "wide_out.obj")
    proc = subprocess.run([exe, "skin", mesh, "--skeleton", wide_sk, "--weights", os.path.join(work, "tip.skw"),
                           "--pose", pose, "--out", skinned], capture_output=True, text=True, timeout=60)
    check(proc.returncode == 0, f"wide {case}: skin exit {proc.returncode} ({proc.stderr.strip()})")
    if proc.returncode != 0:
        continue
    with open(skinned) as f:
        vertex = [float(x) for x in next(line for line in f if line.startswith("v ")).split()[1:4]]
    check(dist(vertex, doc["effector"]) <= 1e-4,
          f"wide {case} {solver}: skin --pose puts the effector at {vertex}, ik printed {doc['effector']}")
check(beyond_90 >= 5, f"wide: only {beyond_90} printed joints beyond ±90° about y: the test does not exercise them")

# --limits swing-twist: per joint a cone and a twist range derived from the Euler limits (docs/cli.md). Checked here
# with this script's own split: swing = the shortest arc taking the bone axis where the rotation takes it, twist =
# the rest; the printed angles are exact (unclamped), so `deform skin --no-limits` reproduces the effector.
# --- two-bone rig settings: shoulder (head (0, 1, 0)) -> elbow -> wrist, both bones of length 1, the elbow bending
# about its -y (toward +z of the shoulder's frame) within its limits.
SHOULDER = (0.0, 1.0, 0.0)


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


def across(v, d):  # the part of v across the unit direction d
    k = dot(v, d)
    return tuple(x - k * y for x, y in zip(v, d))


def unit(v):
    n = math.sqrt(dot(v, v))
    return tuple(x / n for x in v)


def within_swing_twist(rotation, axis, lim, slack=1e-3):
    a = unit(axis)
    t = max(range(3), key=lambda k: abs(a[k]))
    i, j = (t + 1) % 3, (t + 2) % 3
    lo, hi = lim[t] if a[t] >= 0 else (-lim[t][1], -lim[t][0])
    cone = [math.radians(min(180, max(abs(lim[k][0]), abs(lim[k][1])))) for k in (i, j)]
    e = [0.0, 0.0, 0.0]
    e[i] = 1.0
    ref = unit(tuple(x - dot(e, a) * y for x, y in zip(e, a)))
    b2 = cross(a, ref)
    q = q_euler(rotation)
    moved = qrot(q, a)
    n = cross(a, moved)
    angle = math.atan2(math.sqrt(dot(n, n)), dot(a, moved))
    u = unit(n) if dot(n, n) > 1e-20 else ref
    s1, s2 = angle * dot(u, ref), angle * dot(u, b2)
    r = sum((sv / c) ** 2 if c > 0 else (0 if abs(sv) < slack else 2) for sv, c in zip((s1, s2), cone))
    h = math.sin(angle / 2)
    swing = (math.cos(angle / 2), u[0] * h, u[1] * h, u[2] * h)
    tw = qmul((swing[0], -swing[1], -swing[2], -swing[3]), q)
    if tw[0] < 0:
        tw = tuple(-x for x in tw)
    tau = math.degrees(2 * math.atan2(dot(tw[1:], a), tw[0]))
    return r <= 1 + slack and (lo - 0.1 <= tau <= hi + 0.1 or (abs(abs(tau) - 180) < 0.1 and (lo <= -179.9 or hi >= 179.9)))


for case in range(8):
    solver = ("ccd", "fabrik")[case % 2]
    angles = {b[0]: {"rotation": [rng.uniform(lo, hi) for lo, hi in b[4]]} for b in WIDE[1:5]}
    target = head_of("tip", angles)
    code, out, err = run(wide_sk, "--effector", "tip", "--root", "j1", "--solver", solver, "--limits", "swing-twist",
                         "--target", ",".join("%.6f" % x for x in target))
    check(code == 0, f"swing-twist {case}: exit {code} ({err.strip()})")
    if code != 0:
        continue
    doc = json.loads(out)
    check(list(doc) == ["solver", "reached", "distance", "iterations", "effector", "bones"], f"swing-twist keys {list(doc)}")
    names = [b[0] for b in WIDE]
    for name, entry in doc["bones"].items():
        if name == "tip":
            continue
        child = WIDE[names.index(name) + 1]
        check(within_swing_twist(entry["rotation"], child[2], limits_of[name]),
              f"swing-twist {case} {solver}: {name} {entry['rotation']} outside its cone or twist range")
    check(dist(head_of("tip", doc["bones"]), doc["effector"]) <= 1e-4, f"swing-twist {case}: FK of printed bones")
    with open(pose, "w") as f:
        json.dump({"bones": doc["bones"]}, f)
    proc = subprocess.run([exe, "skin", mesh, "--skeleton", wide_sk, "--weights", os.path.join(work, "tip.skw"),
                           "--pose", pose, "--no-limits", "--out", skinned], capture_output=True, text=True, timeout=60)
    check(proc.returncode == 0, f"swing-twist {case}: skin exit {proc.returncode}")
    if proc.returncode == 0:
        with open(skinned) as f:
            vertex = [float(x) for x in next(line for line in f if line.startswith("v ")).split()[1:4]]
        check(dist(vertex, doc["effector"]) <= 1e-4, f"swing-twist {case}: skin --no-limits gives {vertex}")
for args, what in (((wide_sk, "--effector", "tip", "--target", "1,1,1", "--limits", "cone"), "unknown --limits"),
                   ((sk, "--effector", "hand", "--root", "elbow", "--target", "1,1,1", "--solver", "two-bone",
                     "--limits", "swing-twist"), "swing-twist with two-bone")):
    code, out, err = run(*args)
    check(code == 2 and out == "" and "--limits" in err, f"{what}: exit {code}, stderr {err.strip()!r}")
BONES = saved
def two_bone(target, *flags):
    code, out, err = run(sk, "--effector", "wrist", "--root", "shoulder", "--solver", "two-bone", "--target",
                         ",".join(map(str, target)), *flags)
    check(code == 0, f"two-bone {flags}: exit {code} ({err.strip()})")
    return json.loads(out) if code == 0 else None


# --pole (a world point): the elbow lies in the plane of shoulder, target and pole, on the pole's side; --swivel 90
# turns it a quarter turn about shoulder -> target (right-handed).
target, pole = (1.2, 1.9, 0.6), (0.5, 1.0, 2.0)
d = unit(sub(target, SHOULDER))
pole_across = unit(across(sub(pole, SHOULDER), d))
for swivel, expected in ((None, pole_across), ("90", cross(d, pole_across))):
    flags = ("--pole", "0.5,1,2") + (("--swivel", swivel) if swivel else ())
    doc = two_bone(target, *flags)
    if doc:
        check(doc["reached"] is True, f"two-bone {flags}: reached {doc['reached']} distance {doc['distance']}")
        elbow = across(sub(head_of("elbow", doc["bones"]), SHOULDER), d)
        check(dot(unit(elbow), expected) > 1 - 1e-6, f"two-bone {flags}: elbow direction {unit(elbow)} vs {expected}")
        check(dist(head_of("wrist", doc["bones"]), target) <= 1e-4, f"two-bone {flags}: FK of printed bones")
        check("stretch" not in doc, f"two-bone {flags}: no stretch key without --stretch")

# --soften: a target at full reach (2 from the shoulder) is met without it and falls short by soften x 2 / e with it.
full = (SHOULDER[0] + 1.2, SHOULDER[1] + 1.6, 0.0)
previous = 0.0
for soften in ("0", "0.1", "0.2"):
    doc = two_bone(full, "--pole", "0,1,1", "--soften", soften)
    if doc:
        expected = float(soften) * 2.0 / math.e
        check(abs(doc["distance"] - expected) <= 1e-4, f"--soften {soften}: distance {doc['distance']} vs {expected}")
        check(doc["reached"] is (soften == "0"), f"--soften {soften}: reached {doc['reached']}")
        check(doc["distance"] >= previous, f"--soften {soften}: farther than a smaller soften")
        previous = doc["distance"]

# --stretch: 2.6 from the shoulder needs 1.3; up to 1.5 it reaches with both bones 1.3 long (the printed
# translations carry it), with 1.2 it stops 0.2 short.
far = (SHOULDER[0] + 1.56, SHOULDER[1] + 2.08, 0.0)
for max_stretch, factor, distance in (("1.5", 1.3, 0.0), ("1.2", 1.2, 0.2)):
    doc = two_bone(far, "--pole", "0,1,1", "--stretch", max_stretch)
    if doc:
        check(list(doc) == ["solver", "reached", "distance", "iterations", "stretch", "effector", "bones"],
              f"--stretch: keys {list(doc)}")
        check(abs(doc["stretch"] - factor) <= 1e-5, f"--stretch {max_stretch}: stretch {doc['stretch']} vs {factor}")
        check(abs(doc["distance"] - distance) <= 1e-4, f"--stretch {max_stretch}: distance {doc['distance']}")
        check(doc["reached"] is (distance == 0.0), f"--stretch {max_stretch}: reached {doc['reached']}")
        for bone in ("elbow", "wrist"):
            length = math.sqrt(dot(doc["bones"][bone]["translation"], doc["bones"][bone]["translation"]))
            check(abs(length - factor) <= 1e-5, f"--stretch {max_stretch}: {bone} translation length {length}")
        check(dist(head_of("wrist", doc["bones"]), doc["effector"]) <= 1e-4, f"--stretch {max_stretch}: FK of bones")

# --pole with the chain solvers (IkJob::pole): the elbow ends on the pole's side of shoulder -> target, for a pole on
# either side, and the target is still reached.
for solver in ("ccd", "fabrik"):
    for pole in ((0.5, 1.0, 2.0), (0.5, 1.0, -2.0)):
        code, out, err = run(sk, "--effector", "wrist", "--root", "shoulder", "--solver", solver, "--target",
                             ",".join(map(str, target)), "--pole", ",".join(map(str, pole)))
        check(code == 0, f"{solver} --pole {pole}: exit {code} ({err.strip()})")
        if code == 0:
            doc = json.loads(out)
            check(doc["reached"] is True, f"{solver} --pole {pole}: not reached ({doc['distance']})")
            elbow = across(sub(head_of("elbow", doc["bones"]), SHOULDER), d)
            side = dot(unit(elbow), unit(across(sub(pole, SHOULDER), d)))
            check(side > 0.9, f"{solver} --pole {pole}: the elbow is not on the pole's side ({side})")

# The other rig flags are the two-bone solver's: another solver, or a value out of range, is exit 2.
for args, what in (
    (("--solver", "fabrik", "--soften", "0.1"), "--soften with fabrik"),
    (("--stretch", "2"), "--stretch with ccd"),
    (("--solver", "two-bone", "--root", "shoulder", "--soften", "1.5"), "--soften above 1"),
    (("--solver", "two-bone", "--root", "shoulder", "--soften", "-0.1"), "--soften below 0"),
    (("--solver", "two-bone", "--root", "shoulder", "--stretch", "0.5"), "--stretch below 1"),
    (("--solver", "two-bone", "--root", "shoulder", "--stretch", "inf"), "--stretch infinite"),
    (("--solver", "two-bone", "--root", "shoulder", "--swivel", "400"), "--swivel beyond 360"),
    (("--solver", "two-bone", "--root", "shoulder", "--pole", "1,nan,0"), "--pole not finite"),
    (("--solver", "two-bone", "--root", "shoulder", "--pole", "1,1"), "--pole with two numbers"),
):
    code, out, err = run(sk, "--effector", "wrist", "--target", "1,1,1", *args)
    check(code == 2 and out == "" and err != "", f"{what}: exit {code}, stdout {out!r}, stderr {err.strip()!r}")

print("ik CLI:", "FAILED" if failures else "ok", f"({len(failures)} failures)")
sys.exit(1 if failures else 0)
