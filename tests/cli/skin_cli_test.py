#!/usr/bin/env python3
"""`deform skin` end to end: output OBJ layout, bind pose identity, an exact rigid root rotation checked against
math done here, DOF limits and --no-limits, JSON summary, and exit 2 (with nothing written) on bad input.
Usage: skin_cli_test.py DEFORM SAMPLES_DATA WORK_DIR"""
import json, math, os, shutil, subprocess, sys

deform, samples, work = sys.argv[1], sys.argv[2], sys.argv[3]
shutil.rmtree(work, ignore_errors=True)
os.makedirs(work)
failures = []


def check(condition, message):
    if not condition:
        failures.append(message)


def run(*args):
    p = subprocess.run([deform, "skin", *args], capture_output=True, text=True, timeout=120)
    return p.returncode, p.stdout, p.stderr


def write(name, text):
    path = os.path.join(work, name)
    with open(path, "w") as f:
        f.write(text)
    return path


def read_obj(path):
    v, vn, faces = [], [], 0
    with open(path) as f:
        for line in f:
            t = line.split()
            if not t:
                continue
            if t[0] == "v":
                v.append(tuple(map(float, t[1:4])))
            elif t[0] == "vn":
                vn.append(tuple(map(float, t[1:4])))
            elif t[0] == "f":
                faces += 1
    return v, vn, faces


mesh = os.path.join(samples, "builtin.obj")
triple = [mesh, "--skeleton", os.path.join(samples, "builtin.sk"), "--weights", os.path.join(samples, "builtin.skw")]
rest_v, rest_vn, rest_faces = read_obj(mesh)
bind = write("bind.json", '{"bones": {}}')

# Bind pose, every method, both model sources: every v back where it was, same counts, faces kept.
for method in ("lbs", "dqs", "ddm"):
    for source in (triple, ["--builtin"]):
        out = os.path.join(work, f"bind_{method}_{len(source)}.obj")
        rc, stdout, stderr = run(*source, "--pose", bind, "--method", method, "--out", out)
        check(rc == 0, f"bind {method} {source[0]}: exit {rc}: {stderr}")
        if rc != 0:
            continue
        summary = json.loads(stdout)
        check(summary["method"] == method and summary["vertices"] == len(rest_v), f"summary {summary}")
        check(summary["bones_posed"] == 0 and summary["max_displacement"] < 1e-5, f"bind summary {summary}")
        check(summary["out"] == out, "out path in summary")
        v, vn, faces = read_obj(out)
        check(len(v) == len(rest_v) and len(vn) == len(rest_vn) and faces == rest_faces, "bind: counts differ")
        worst = max(max(abs(a - b) for a, b in zip(p, q)) for p, q in zip(v, rest_v))
        check(worst < 1e-5, f"bind {method}: a vertex moved by {worst}")

# Rotating the root about X by 30° moves every vertex rigidly about the root's head (0, 0.95, 0): LBS and DQS both
# give p' = H + Rx(30°) (p - H) and n' = Rx(30°) n. The hips' bind rotation is [90, 0, 0]. Direct Delta Mush too: the
# whole skeleton moves rigidly, so every point's rotation is Rx(30°).
pose = write("root.json", '{"bones": {"hips": {"rotation": [120, 0, 0]}}}')
c, s = math.cos(math.radians(30)), math.sin(math.radians(30))
rx = lambda p: (p[0], c * p[1] - s * p[2], s * p[1] + c * p[2])
for method in ("lbs", "dqs", "ddm"):
    out = os.path.join(work, f"root_{method}.obj")
    rc, stdout, stderr = run(*triple, "--pose", pose, "--method", method, "--out", out)
    check(rc == 0, f"root {method}: exit {rc}: {stderr}")
    if rc != 0:
        continue
    summary = json.loads(stdout)
    check(summary["bones_posed"] == 1, f"root {method}: bones_posed {summary['bones_posed']}")
    v, vn, _ = read_obj(out)
    worst = 0.0
    for p, q in zip(rest_v, v):
        r = rx((p[0], p[1] - 0.95, p[2]))
        expected = (r[0], r[1] + 0.95, r[2])
        worst = max(worst, max(abs(a - b) for a, b in zip(expected, q)))
    check(worst < 1e-4, f"root {method}: off by {worst}")
    _, bind_vn, _ = read_obj(os.path.join(work, "bind_lbs_5.obj"))  # `vn` lines as the writer orders them
    check(len(vn) == len(bind_vn) > 0, "root: normal count")
    worst_n = max(max(abs(a - b) for a, b in zip(rx(n), m)) for n, m in zip(bind_vn, vn))
    check(worst_n < 1e-4, f"root {method}: normals off by {worst_n}")
    lo, hi = summary["bounds"]["min"], summary["bounds"]["max"]
    check(all(abs(lo[k] - min(p[k] for p in v)) < 1e-6 for k in range(3)), f"bounds min {lo}")
    check(all(abs(hi[k] - max(p[k] for p in v)) < 1e-6 for k in range(3)), f"bounds max {hi}")

# DOF limits: the left forearm's Z axis is locked at 0, so a Z rotation is clamped away unless --no-limits.
bend = write("bend.json", '{"bones": {"forearm_l": {"rotation": [0, 0, 90]}}}')
out = os.path.join(work, "bend.obj")
rc, stdout, stderr = run("--builtin", "--pose", bend, "--out", out)
check(rc == 0 and json.loads(stdout)["max_displacement"] < 1e-5, f"clamped bend moved the mesh: {stdout} {stderr}")
rc, stdout, stderr = run("--builtin", "--pose", bend, "--no-limits", "--method", "dqs", "--out", out)
check(rc == 0 and json.loads(stdout)["max_displacement"] > 0.1, f"--no-limits bend: {stdout} {stderr}")
check(rc == 0 and json.loads(stdout)["limits"] is False, "--no-limits not reported")

# --mush N: Delta Mush after skinning. The bind pose comes back (to 1e-6 of the size, the OBJ's 9 digits aside); a
# bent elbow is smoothed: the mushed points differ from plain LBS near the elbow only, and the summary says so.
size = math.dist(*[tuple(f(c[i] for c in rest_v) for i in range(3)) for f in (min, max)])
out = os.path.join(work, "mush_bind.obj")
rc, stdout, stderr = run("--builtin", "--pose", bind, "--mush", "10", "--out", out)
check(rc == 0 and json.loads(stdout)["mush"] == {"iterations": 10, "step": 0.5}, f"--mush at bind: {stdout} {stderr}")
if rc == 0:
    mushed_v = read_obj(out)[0]
    worst = max(math.dist(a, b) for a, b in zip(mushed_v, rest_v))
    check(worst < 2e-6 * size, f"--mush 10 at the bind pose moved a point by {worst / size} of the size")
elbow = write("elbow.json", '{"bones": {"forearm_l": {"rotation": [110, 0, 0]}}}')
plain, mushed = os.path.join(work, "elbow_lbs.obj"), os.path.join(work, "elbow_mush.obj")
rc1, _, _ = run("--builtin", "--pose", elbow, "--out", plain)
rc2, stdout, stderr = run("--builtin", "--pose", elbow, "--mush", "10", "--mush-step", "0.7", "--out", mushed)
check(rc1 == 0 and rc2 == 0, f"--mush on a bent elbow: exit {rc2}: {stderr}")
if rc1 == 0 and rc2 == 0:
    check(json.loads(stdout)["mush"] == {"iterations": 10, "step": 0.7}, f"--mush summary {stdout}")
    a, b = read_obj(plain), read_obj(mushed)
    moved = [math.dist(p, q) for p, q in zip(a[0], b[0])]
    check(max(moved) > 1e-3 * size, "--mush did not smooth the bent elbow")
    check(sum(m > 1e-5 * size for m in moved) < len(moved) / 2, "--mush moved more than the arm")
    check(len(a[1]) == len(b[1]) and a[2] == b[2], "--mush changed the OBJ's layout")

# --method ddm on a bent elbow: the summary names it, the arm moves, and the points differ from LBS's near the elbow
# (smoothed) but not everywhere.
ddm = os.path.join(work, "elbow_ddm.obj")
rc1, _, _ = run("--builtin", "--pose", elbow, "--out", plain)
rc2, stdout, stderr = run("--builtin", "--pose", elbow, "--method", "ddm", "--out", ddm)
check(rc1 == 0 and rc2 == 0, f"--method ddm on a bent elbow: exit {rc2}: {stderr}")
if rc1 == 0 and rc2 == 0:
    summary = json.loads(stdout)
    check(summary["method"] == "ddm" and summary["max_displacement"] > 0.05, f"--method ddm summary {summary}")
    a, b = read_obj(plain), read_obj(ddm)
    moved = [math.dist(p, q) for p, q in zip(a[0], b[0])]
    check(max(moved) > 1e-3 * size, "--method ddm gave LBS's points at the bent elbow")
    check(sum(m > 1e-3 * size for m in moved) < len(moved) / 2, "--method ddm moved more than the arm")
    check(len(a[1]) == len(b[1]) and a[2] == b[2], "--method ddm changed the OBJ's layout")
    check(all(abs(math.hypot(*n) - 1.0) < 1e-5 for n in b[1]), "--method ddm: normals not unit")
    # --ddm-variant reduced: the same layout, near the full form's points but not equal to them; full is the default.
    reduced = os.path.join(work, "elbow_ddm_reduced.obj")
    full = os.path.join(work, "elbow_ddm_full.obj")
    rc3, _, stderr = run("--builtin", "--pose", elbow, "--method", "ddm", "--ddm-variant", "reduced", "--out", reduced)
    rc4, _, _ = run("--builtin", "--pose", elbow, "--method", "ddm", "--ddm-variant", "full", "--out", full)
    check(rc3 == 0 and rc4 == 0, f"--ddm-variant: exit {rc3}, {rc4}: {stderr}")
    if rc3 == 0 and rc4 == 0:
        c, d = read_obj(reduced), read_obj(full)
        check(d == b, "--ddm-variant full is not the default")
        gap = [math.dist(p, q) for p, q in zip(b[0], c[0])]
        check(1e-5 * size < max(gap) < 0.05 * size, f"--ddm-variant reduced: {max(gap) / size} of the size from full")
        check(len(c[1]) == len(b[1]) and c[2] == b[2], "--ddm-variant reduced changed the OBJ's layout")
        check(all(abs(math.hypot(*n) - 1.0) < 1e-5 for n in c[1]), "--ddm-variant reduced: normals not unit")

# Invalid input: exit 2, nothing on stdout, a message naming the problem, and an existing output left untouched.
existing = write("existing.obj", "keep me\n")
short_mesh = write("short.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
bad_cases = [
    (["--builtin", "--pose", write("unknown.json", '{"bones": {"nope": {"rotation": [1, 2, 3]}}}')], "nope"),
    (["--builtin", "--pose", write("nan.json", '{"bones": {"hips": {"rotation": [1, 2]}}}')], "hips"),
    (["--builtin", "--pose", os.path.join(work, "missing.json")], "missing.json"),
    (["--builtin", "--pose", bind, "--method", "slerp"], "--method"),
    (["--builtin"], "--pose"),
    ([mesh, "--builtin", "--pose", bind], "--builtin"),
    ([mesh, "--skeleton", triple[2], "--pose", bind], "--weights"),
    ([short_mesh, "--skeleton", triple[2], "--weights", triple[4], "--pose", bind], "builtin.skw"),
    ([os.path.join(work, "absent.obj"), "--skeleton", triple[2], "--weights", triple[4], "--pose", bind], "absent.obj"),
    (["--builtin", "--pose", bind, "--mush", "-1"], "--mush"),
    (["--builtin", "--pose", bind, "--mush", "10001"], "--mush"),
    (["--builtin", "--pose", bind, "--mush", "2.5"], "--mush"),
    (["--builtin", "--pose", bind, "--mush", "10", "--mush-step", "nan"], "--mush-step"),
    (["--builtin", "--pose", bind, "--mush", "10", "--mush-step", "0"], "--mush-step"),
    (["--builtin", "--pose", bind, "--mush-step", "0.5"], "--mush-step needs --mush"),
    (["--builtin", "--pose", bind, "--ddm-variant", "reduced"], "--ddm-variant needs --method ddm"),
    (["--builtin", "--pose", bind, "--method", "ddm", "--ddm-variant", "v2"], "--ddm-variant"),
]
for args, mention in bad_cases:
    rc, stdout, stderr = run(*args, "--out", existing)
    check(rc == 2, f"{args}: exit {rc}, expected 2 ({stderr})")
    check(stdout == "", f"{args}: printed {stdout!r}")
    check(mention in stderr, f"{args}: stderr {stderr!r} does not mention {mention!r}")
    with open(existing) as f:
        check(f.read() == "keep me\n", f"{args}: the existing output was touched")
rc, stdout, stderr = run("--builtin", "--pose", bind)
check(rc == 2 and "--out" in stderr, f"missing --out: exit {rc}")

# An output path that is not UTF-8: written, and the summary still printed (exit 0), the path shown with U+FFFD.
odd = os.path.join(work.encode(), b"\xff\xfe.obj")
p = subprocess.run([deform.encode(), b"skin", b"--builtin", b"--pose", bind.encode(), b"--out", odd], capture_output=True,
                   timeout=120)
check(p.returncode == 0, f"non-UTF-8 output path: exit {p.returncode} ({p.stderr!r})")
check(os.path.exists(odd), "non-UTF-8 output path: no file written")
check("\ufffd" in p.stdout.decode("utf-8", "replace"), "non-UTF-8 output path: not in the summary")

for failure in failures:
    print("FAIL:", failure)
print(f"{0 if failures else 1} passed, {len(failures)} failed")
sys.exit(1 if failures else 0)
