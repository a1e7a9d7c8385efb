#!/usr/bin/env bash
# `uniform` at 16/64/256/1024 VPLs against the exhaustive `all` on the default scene,
# indirect component, 128², DPRSM 128² per face (32768 VPL slots). Prints a Markdown table.
# Usage: lab/bench-uniform.sh [output dir]   (CARGO_TARGET_DIR is honoured)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-uniform}"
mkdir -p "$out"
cargo build -q -p bounce
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
scene=assets/cornell-box/scene.toml
common=(--width 128 --height 128 --component indirect --dprsm-res 128 --voxels 128)
gpu_ms() { grep -E '^total' | awk '{print $2}'; }
t_all=$("$bin" render "$scene" "${common[@]}" --method all --out "$out/all.exr" --timings 2>/dev/null | gpu_ms)
echo "| method | VPLs/pixel | GPU ms | relMSE vs all | mean ratio |"
echo "|---|---:|---:|---:|---:|"
echo "| all | 32768 slots | $t_all | 0 | 1 |"
for n in 16 64 256 1024; do
  t=$("$bin" render "$scene" "${common[@]}" --method uniform --vpls "$n" --out "$out/uniform-$n.exr" --timings 2>/dev/null | gpu_ms)
  m=$("$bin" compare "$out/uniform-$n.exr" "$out/all.exr" --json)
  rel=$(echo "$m" | sed -E 's/.*"rel_mse": ([^,]+),.*/\1/')
  ratio=$(echo "$m" | sed -E 's/.*"mean_ratio": ([^,]+),.*/\1/')
  printf '| uniform | %s | %s | %.4g | %.4f |\n' "$n" "$t" "$rel" "$ratio"
done
