#!/usr/bin/env bash
# every selection method at 64/256/1024 VPLs per pixel against the exhaustive `all`,
# indirect component, 128², DPRSM 128² per face, 128 voxels. GPU time is the sum of the frame's pass
# timestamps (`--timings` total). Prints a Markdown table.
# Usage: lab/bench-methods.sh <scene.toml> [output dir]   (CARGO_TARGET_DIR is honoured)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
scene="$1"
out="${2:-${CARGO_TARGET_DIR:-target}/bench-methods/$(basename "$(dirname "$scene")")}"
mkdir -p "$out"
cargo build -q -p bounce
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
common=(--width 128 --height 128 --component indirect --dprsm-res 128 --voxels 128)
gpu_ms() { grep -E '^total' | awk '{print $2}'; }
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
[ -f "$out/all.exr" ] || "$bin" render "$scene" "${common[@]}" --method all --out "$out/all.exr" 2>/dev/null
echo "| method | 64 VPLs: GPU ms | relMSE | 256: GPU ms | relMSE | 1024: GPU ms | relMSE |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for m in uniform global stratified local gbg mis; do
  row="| $m"
  for n in 64 256 1024; do
    t=$("$bin" render "$scene" "${common[@]}" --method "$m" --vpls "$n" --out "$out/$m-$n.exr" --timings 2>/dev/null | gpu_ms)
    r=$("$bin" compare "$out/$m-$n.exr" "$out/all.exr" --json | field rel_mse)
    row="$row | $(printf '%.0f' "$t") | $(printf '%.4g' "$r")"
  done
  echo "$row |"
done
