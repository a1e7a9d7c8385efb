#!/usr/bin/env bash
# The 1/d² clamp: its bias (clamped `all` against unclamped `all`) and what it buys (`uniform` error
# against the unclamped `all`). Default scene, indirect, 128², DPRSM 128². Needs the `all` image of
# lab/bench-uniform.sh in the same output directory. Prints a Markdown table.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-uniform}"
cargo build -q -p bounce --features lab  # --clamp is a lab switch
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
scene=assets/cornell-box/scene.toml
common=(--width 128 --height 128 --component indirect --dprsm-res 128 --voxels 128)
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
echo "| clamp (× diagonal) | bias of clamped all: relMSE vs all | mean ratio | uniform 256: relMSE vs all | uniform 1024: relMSE vs all |"
echo "|---:|---:|---:|---:|---:|"
for c in 0 0.005 0.01 0.02; do
  if [ "$c" = 0 ]; then b_rel=0; b_ratio=1; else
    "$bin" render "$scene" "${common[@]}" --method all --clamp "$c" --out "$out/all-clamp-$c.exr" 2>/dev/null
    m=$("$bin" compare "$out/all-clamp-$c.exr" "$out/all.exr" --json); b_rel=$(echo "$m" | field rel_mse); b_ratio=$(echo "$m" | field mean_ratio)
  fi
  row="| $c | $(printf '%.3g' "$b_rel") | $(printf '%.4f' "$b_ratio")"
  for n in 256 1024; do
    "$bin" render "$scene" "${common[@]}" --method uniform --vpls "$n" --clamp "$c" --out "$out/u$n-clamp-$c.exr" 2>/dev/null
    r=$("$bin" compare "$out/u$n-clamp-$c.exr" "$out/all.exr" --json | field rel_mse)
    row="$row | $(printf '%.4g' "$r")"
  done
  echo "$row |"
done
