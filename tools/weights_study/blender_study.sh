#!/bin/sh
# Libdeform's bone heat side by side with Blender's ("With Automatic Weights") on the six rigged characters of
# Debian's assimp-testmodels, in the same seeded random poses (docs/weights.md, "Side by side with Blender").
#
#   tools/weights_study/blender_study.sh [WEIGHTS_STUDY [DIR [weights_study options...]]]
#
# WEIGHTS_STUDY: the built tool (default build/tools/weights_study); DIR: where the bind meshes and Blender's weights
# go (default a fresh temporary folder); the options (default --random-poses 32 --seed 1) go to both runs of the
# tool, so that Blender is given the same deforming bones. Installs Debian's blender with apt-get when it is missing.
# Not run by the test suite: the suite does not need Blender.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
study=${1:-build/tools/weights_study}
dir=${2:-$(mktemp -d)}
[ $# -gt 2 ] && shift 2 || set --
[ $# -gt 0 ] || set -- --random-poses 32 --seed 1
if ! command -v blender >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then apt-get install -y blender; else sudo apt-get install -y blender; fi
fi
models=/usr/share/assimp/models
set -- "$@" "$models/X/Testwuson.X" "$models/X/BCN_Epileptic.X" "$models/X/anim_test.x" \
  "$models/FBX/animation_with_skeleton.fbx" "$models/FBX/huesitos.fbx" "$models/IQM/mrfixit.iqm"
"$study" --blender-export "$dir" "$@" >/dev/null
blender --background --factory-startup --python "$here/blender_heat.py" -- "$dir" 2>&1 |
  grep -E 'unweighted|Heat|heat|Error' || true
"$study" --blender-weights "$dir" "$@"
