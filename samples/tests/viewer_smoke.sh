#!/usr/bin/env bash
# Smoke test of the viewer under Xvfb with Mesa's software renderer: a frame before a reach and one after it,
# both non-blank, the character covering a plausible share of pixels, and the two different. Also one full
# (non-bare) screenshot.  usage: viewer_smoke.sh VIEWER PNG_CHECK WORKDIR
set -euo pipefail
viewer=$1 check=$2 work=$3
mkdir -p "$work"
run() { xvfb-run -a -s "-screen 0 640x480x24" "$viewer" --width 640 --height 480 "$@"; }
run --bare --screenshot "$work/before.png" --frames 20
run --bare --screenshot "$work/after.png" --frames 40 --reach 1.3,1.6,0.4 --at 2
"$check" "$work/before.png" "$work/after.png"
run --screenshot "$work/full.png" --frames 30 --reach 1.3,1.6,0.4 --at 2 --release-at 20 >/dev/null
test -s "$work/full.png"
echo "viewer smoke test passed"
