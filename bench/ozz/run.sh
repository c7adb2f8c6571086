#!/bin/sh
# libdeform beside ozz-animation (docs/performance.md): builds ozz's runtime and offline libraries from the source
# tree given, builds and installs libdeform's libraries (Release, the project's own flags) unless DEFORM_PREFIX names
# an installed libdeform, builds bench/ozz against both and Debian's Google Benchmark, and runs it.
#   bench/ozz/run.sh OZZ_SOURCE_DIR [benchmark arguments]
# Without benchmark arguments: 9 repetitions of each benchmark, interleaved at random, medians and spread only.
# Environment: DEFORM_OZZ_BUILD (the build folder, default build-ozz-bench/ in the repository), DEFORM_PREFIX,
# OZZ_SIMD_FLAGS (extra flags for ozz, e.g. "-mavx2 -mfma"; default none: the x86-64 baseline, ozz's SSE2 path),
# and CMake's own (CXX, CMAKE_CXX_COMPILER_LAUNCHER, CMAKE_BUILD_PARALLEL_LEVEL).
# Measured with ozz-animation 0.16.0, commit 6cbdc790123aa4731d82e255df187b3a8a808256.
set -eu
if [ $# -lt 1 ] || [ ! -f "$1/include/ozz/animation/runtime/sampling_job.h" ]; then
  echo "usage: $0 OZZ_SOURCE_DIR [benchmark arguments]  (OZZ_SOURCE_DIR: an ozz-animation source tree)" >&2
  exit 2
fi
ozz=$(cd "$1" && pwd)
shift
root=$(cd "$(dirname "$0")/../.." && pwd)
build=${DEFORM_OZZ_BUILD:-$root/build-ozz-bench}
flags=${OZZ_SIMD_FLAGS:-}

prefix=${DEFORM_PREFIX:-}
if [ -z "$prefix" ]; then
  cmake -S "$root" -B "$build/libdeform" -DCMAKE_BUILD_TYPE=Release -DDEFORM_LIBRARY_ONLY=ON \
    -DDEFORM_BUILD_IMPORT=OFF -DDEFORM_BUILD_GPU=OFF >/dev/null
  cmake --build "$build/libdeform"
  cmake --install "$build/libdeform" --prefix "$build/prefix" >/dev/null
  prefix=$build/prefix
fi

# One build folder per ozz flag set, so the two builds can be kept side by side.
tag=$(printf '%s' "${flags:-baseline}" | tr -c 'A-Za-z0-9' '_')
cmake -S "$root/bench/ozz" -B "$build/bench-$tag" -DCMAKE_BUILD_TYPE=Release -DOZZ_SOURCE_DIR="$ozz" \
  -DCMAKE_PREFIX_PATH="$prefix" -DOZZ_SIMD_FLAGS="$flags" >/dev/null
cmake --build "$build/bench-$tag" --target deform_beside_ozz

echo "ozz source: $ozz, commit $(git -C "$ozz" rev-parse HEAD 2>/dev/null || echo '(not a git work tree)')"
echo "ozz extra flags: ${flags:-none}"
if [ $# -eq 0 ]; then
  set -- --benchmark_repetitions=9 --benchmark_enable_random_interleaving=true \
    --benchmark_report_aggregates_only=true --benchmark_min_time=0.2
fi
exec "$build/bench-$tag/deform_beside_ozz" "$@"
