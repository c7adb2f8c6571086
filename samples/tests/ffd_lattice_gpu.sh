#!/bin/sh
# ffd_lattice_gpu.sh XVFB_RUN SAMPLE PNG_CHECK DIR: renders the ffd_lattice sample headless with the CPU and the GPU
# evaluation and checks that the GPU really ran and that the two pictures are the same (png_check --same-picture).
# Skips (exit 0) only when the context lacks OpenGL 4.3.
set -e
xvfb="$1" sample="$2" check="$3" dir="$4"
mkdir -p "$dir"
"$xvfb" -a "$sample" --screenshot "$dir/cpu.png" --frames 40
"$xvfb" -a "$sample" --gpu --screenshot "$dir/gpu.png" --frames 40 > "$dir/gpu.log" 2>&1 || { cat "$dir/gpu.log"; exit 1; }
cat "$dir/gpu.log"
if grep -q "is not OpenGL 4.3" "$dir/gpu.log"; then
  echo "skipped: no OpenGL 4.3"
  exit 0
fi
grep -q "evaluating on the GPU" "$dir/gpu.log"
"$check" --same-picture "$dir/cpu.png" "$dir/gpu.png"
