#!/usr/bin/env bash
# Where the error of a VPL image comes from: visibility (voxel vs exact), VPL discretisation
# (all with exact visibility vs the path-traced reference) and selection (a method vs all). Default scene,
# 64², indirect, DPRSM 128², 128 voxels, reference 4096 spp. Prints a Markdown table.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-error-split}"
mkdir -p "$out"
cargo build -q -p bounce
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
scene=assets/cornell-box/scene.toml
common=(--width 64 --height 64 --component indirect --dprsm-res 128 --voxels 128)
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
"$bin" render "$scene" "${common[@]}" --method reference --spp 4096 --out "$out/reference.exr" 2>"$out/reference.log"
"$bin" render "$scene" "${common[@]}" --method all --out "$out/all-voxel.exr" 2>/dev/null
"$bin" render "$scene" "${common[@]}" --method all --visibility exact --out "$out/all-exact.exr" 2>/dev/null
"$bin" render "$scene" "${common[@]}" --method gbg --vpls 256 --out "$out/gbg-256.exr" 2>/dev/null
row() { m=$("$bin" compare "$2" "$3" --json); printf '| %s | %.4g | %.4f | %.4f |\n' "$1" "$(echo "$m" | field rel_mse)" "$(echo "$m" | field mean_ratio)" "$(echo "$m" | field flip)"; }
echo "| comparison (what it isolates) | relMSE | mean ratio | mean FLIP |"
echo "|---|---:|---:|---:|"
row "all (voxel) vs reference: everything but selection" "$out/all-voxel.exr" "$out/reference.exr"
row "all (voxel) vs all (exact): visibility" "$out/all-voxel.exr" "$out/all-exact.exr"
row "all (exact) vs reference: VPL discretisation (+ reference noise)" "$out/all-exact.exr" "$out/reference.exr"
row "gbg 256 vs all (voxel): selection" "$out/gbg-256.exr" "$out/all-voxel.exr"
grep -o "standard error of the mean [0-9.e+-]*" "$out/reference.log" | sed 's/^/reference: /'
