#!/usr/bin/env bash
# The viewer's weight tools (--weights-tool, the panel's "Weights") under Xvfb: each tool's result, saved with
# --save-weights, has the property the tool promises (sums 1, at most N influences, none below the threshold), the
# weight map painted on the surface shows it (limit:1 leaves no mid weight, so no green; smoothing widens the
# transition, so less red and more green), revert gives the model's own weights back, and a tool that refuses (mirror
# on a mesh made asymmetric) says why and keeps the weights; the character bound again keeps its clip and skinning.
# usage: viewer_weights.sh VIEWER PNG_CHECK WORKDIR
set -euo pipefail
viewer=$1 check=$2 work=$3
mkdir -p "$work"
data=$(cd "$(dirname "$0")/../data" && pwd)
run() { xvfb-run -a -s "-screen 0 640x480x24" "$viewer" --width 400 --height 400 --inertia 0 --frames 3 "$@"; }
map=(--bare --weight-map upperarm_l)
run "${map[@]}" --screenshot "$work/own.png" --save-weights "$work/own.skw" >"$work/own.json"
run "${map[@]}" --screenshot "$work/limit1.png" --weights-tool limit:1 --save-weights "$work/limit1.skw" \
  >"$work/limit1.json"
run "${map[@]}" --screenshot "$work/smooth.png" --weights-tool smooth:10 >/dev/null
run "${map[@]}" --screenshot "$work/edited.png" --weights-tool smooth:4:0.7 --weights-tool prune:0.05 \
  --weights-tool limit:3 --save-weights "$work/edited.skw" >"$work/edited.json"
run "${map[@]}" --screenshot "$work/heat.png" --weights-tool heat:4 --save-weights "$work/heat.skw" >/dev/null
run "${map[@]}" --screenshot "$work/reverted.png" --weights-tool limit:1 --weights-tool revert \
  --save-weights "$work/reverted.skw" >/dev/null
cmp "$work/own.skw" "$work/reverted.skw"
# With the GPU deformation the map reads the points and their normals back from the vertex buffer: the same picture
# as the CPU's (skipped without OpenGL 4.3 compute shaders).
gpu=$(run "${map[@]}" --gpu --weights-tool smooth:10 --screenshot "$work/smooth_gpu.png")
if grep -q '"gpu_lattices": true' <<<"$gpu"; then "$check" --same-picture "$work/smooth.png" "$work/smooth_gpu.png"; fi
# Bound again, the character keeps its clip at its time and the skinning method (DQS here, which draws this walk
# differently from LBS): normalize, which leaves these weights as they are within rounding, draws the same picture.
run --bare --frames 30 --clip walk --dqs --screenshot "$work/walk_dqs.png" >/dev/null
run --bare --frames 30 --clip walk --dqs --weights-tool normalize --screenshot "$work/walk_dqs_tool.png" >/dev/null
"$check" --same-picture "$work/walk_dqs.png" "$work/walk_dqs_tool.png"
# The panel's Weights section, open with its message, over the walk.
run --screenshot "$work/full.png" --clip walk --weight-map forearm_l --weights-tool smooth:2 >/dev/null
test -s "$work/full.png"
for image in own limit1 smooth; do "$check" --colours "$work/$image.png" >"$work/$image.colours"; done

# Refused: mirror on the built-in character's mesh with one point moved off the symmetry (no mirror point within the
# tolerance); the message names the point, the weights stay the model's own, the next tool still runs.
grep -v -e '^mtllib' -e '^usemtl' "$data/builtin.obj" | awk '!moved && /^v / {$2 += 0.03; moved = 1} {print}' \
  >"$work/asymmetric.obj"
asymmetric=("$work/asymmetric.obj" --skeleton "$data/builtin.sk" --weights "$data/builtin.skw" --bare)
run "${asymmetric[@]}" --screenshot "$work/asym.png" --weights-tool normalize --save-weights "$work/asym_own.skw" \
  >/dev/null
run "${asymmetric[@]}" --screenshot "$work/asym_mirror.png" --weights-tool mirror:flip --weights-tool normalize \
  --save-weights "$work/asym_mirror.skw" >"$work/asym_mirror.json" 2>"$work/asym_mirror.err"
grep -q "mirror flip refused: .*point 0 .*has no mirror point" "$work/asym_mirror.err" || {
  cat "$work/asym_mirror.err"
  exit 1
}
cmp "$work/asym_own.skw" "$work/asym_mirror.skw"

python3 - "$work" <<'PY'
import json, sys
work = sys.argv[1]

def read_skw(name):
    lines = open(f"{work}/{name}").read().split("\n")
    assert lines[0] == "skw 1" and lines[1].startswith("vertices "), lines[:2]
    points = []
    for line in lines[2:]:
        if not line.strip():
            continue
        fields = line.split()
        points.append([(int(b), float(w)) for b, w in zip(fields[1::2], fields[2::2])])
    assert len(points) == int(lines[1].split()[1]), name
    return points

def summary(name):
    return json.loads(open(f"{work}/{name}").read())

own, limit1, edited, heat = (read_skw(n) for n in ("own.skw", "limit1.skw", "edited.skw", "heat.skw"))
for name, points in (("own", own), ("limit1", limit1), ("edited", edited), ("heat", heat)):
    worst = max(abs(sum(w for _, w in p) - 1.0) for p in points)
    assert worst < 1e-4, (name, "sums", worst)
assert max(len(p) for p in own) > 1, "the built-in character's weights blend bones: the test needs that"
assert all(len(p) == 1 for p in limit1), "limit:1 left a point with several influences"
assert max(len(p) for p in edited) <= 3, "limit:3 left a point with more than 3 influences"
assert min(w for p in edited for _, w in p) >= 0.05 - 1e-6, "prune:0.05 left a weight below 0.05"
assert heat != own, "heat:4 gave the model's own weights back"
for name, runs in (("limit1.json", 1), ("edited.json", 3), ("asym_mirror.json", 1)):  # (mirror refused, normalize)
    s = summary(name)
    assert s["weight_tools_run"] == runs, (name, s)
    assert s["weight_tools_refused"] == (1 if name == "asym_mirror.json" else 0), (name, s)

# The map painted with the tools' results: blue 0, green 0.5, red 1.
colours = {n: summary(f"{n}.colours") for n in ("own", "limit1", "smooth")}
assert colours["own"]["green"] > 0.01 and colours["own"]["red"] > 0.01, colours
assert colours["limit1"]["green"] == 0.0 and colours["limit1"]["red"] > 0.01, colours  # only 0 and 1 are left
assert colours["smooth"]["red"] < 0.8 * colours["own"]["red"], colours      # the full weight recedes from the seam
assert colours["smooth"]["green"] > colours["own"]["green"], colours        # the transition widens
print("viewer weights ok:", colours)
PY
