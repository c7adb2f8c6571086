#!/bin/sh
# libdeform's Delta Mush against Blender's Corrective Smooth on the built-in character, posed as docs/skinning.md's
# pictures (docs/skinning.md, "Against Blender's Corrective Smooth").
#
#   tools/skinning_study/blender_study.sh [BUILD [DIR [corrective_smooth.py options...]]]
#
# BUILD: the build folder whose python/ holds the deform module (default build); DIR: where the inputs and both
# results go (default a fresh temporary folder); the options (--iterations, --step, --picture) go to both steps of
# corrective_smooth.py. PYTHON: a python3 with NumPy (default Debian's /usr/bin/python3).
# Installs Debian's blender with apt-get when it is missing. Not run by the test suite: the suite does not need
# Blender.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
build=${1:-build}
dir=${2:-$(mktemp -d)}
[ $# -gt 2 ] && shift 2 || set --
python=${PYTHON:-/usr/bin/python3}
if ! command -v blender >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ]; then apt-get install -y blender; else sudo apt-get install -y blender; fi
fi
PYTHONPATH="$build/python" "$python" "$here/corrective_smooth.py" export "$dir" "$@"
blender --background --factory-startup --python "$here/blender_corrective_smooth.py" -- "$dir" 2>&1 |
  grep -E '^Blender [0-9]|Error' || true
PYTHONPATH="$build/python" "$python" "$here/corrective_smooth.py" compare "$dir" "$@"
