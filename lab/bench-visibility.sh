#!/usr/bin/env bash
# The voxel march (at 128 and 256 cells) against exact
# shadow rays, on the default Cornell box, two-rooms and the stress scenes of scripts/make-scenes.py.
# Accuracy: `--method all` (every VPL: the converged sum), indirect component, 64², DPRSM 32² per face; mean
# ratio and relMSE against `all --visibility exact`. Cost: the gather's GPU ms of `--method uniform --vpls
# 256` at the same size, median of three runs (indicative on a shared machine). Prints a Markdown table.
# Usage: lab/bench-visibility.sh [output dir] [scene names...]   (CARGO_TARGET_DIR is honoured)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-visibility}"
shift || true
scenes=("$@")
[ ${#scenes[@]} -gt 0 ] || scenes=(cornell-box two-rooms box-on-floor doorway clutter sibenik conference)
mkdir -p "$out"
cargo build -q -p bounce
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
common=(--width 64 --height 64 --component indirect --dprsm-res 32)
# (label, flags) of each visibility measured against exact.
configs=("voxel 128|--visibility voxel --voxels 128" "voxel 256|--visibility voxel --voxels 256"
  "exact|--visibility exact")
gather_ms() { awk '$1 == "gather" {print $2}'; }
median3() { sort -g | sed -n 2p; }
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
echo "| scene | visibility | mean ratio | relMSE | gather ms (uniform, 256 VPLs, median of 3) |"
echo "|---|---|---:|---:|---:|"
for s in "${scenes[@]}"; do
  scene="assets/$s/scene.toml"
  "$bin" render "$scene" "${common[@]}" --method all --visibility exact --out "$out/$s-exact.exr" >/dev/null 2>&1
  for c in "${configs[@]}"; do
    label="${c%%|*}"
    read -r -a flags <<<"${c#*|}"
    tag="${label// /-}"
    if [ "$label" = exact ]; then
      ratio=1 rel=0
    else
      "$bin" render "$scene" "${common[@]}" --method all "${flags[@]}" --out "$out/$s-$tag.exr" >/dev/null 2>&1
      m=$("$bin" compare "$out/$s-$tag.exr" "$out/$s-exact.exr" --json)
      ratio=$(echo "$m" | field mean_ratio)
      rel=$(echo "$m" | field rel_mse)
    fi
    ms=$(for k in 1 2 3; do
      "$bin" render "$scene" "${common[@]}" --method uniform --vpls 256 "${flags[@]}" --timings \
        --out "$out/$s-$tag-uniform.exr" 2>/dev/null | gather_ms
    done | median3)
    printf '| %s | %s | %.4f | %.3g | %s |\n' "$s" "$label" "$ratio" "$rel" "$ms"
  done
done
