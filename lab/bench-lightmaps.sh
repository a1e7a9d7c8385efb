#!/usr/bin/env bash
# Thesis Tables 6.3 and 6.4, extended with error. Default scene, 64², indirect.
#  A. Light maps: the time to render each VPL map (its `dprsm` pass) and the error of `all` on it against
#     the path-traced reference, at the same resolution per face and at about the same texel budget.
#  B. Per-VPL shadow maps: --visibility psm at --psm-res 64…512 (64 shared VPLs, gbg), its passes' time and
#     its error against `all` with exact visibility;
#     the per-pixel voxel and exact gathers at 64 VPLs for comparison.
# Prints Markdown tables. Usage: lab/bench-lightmaps.sh [output dir]   (CARGO_TARGET_DIR is honoured)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-lightmaps}"
mkdir -p "$out"
cargo build -q -p bounce
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
scene=assets/cornell-box/scene.toml
common=(--width 64 --height 64 --component indirect --voxels 128)
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
pass_ms() { awk -v p="$1" '$1 == p { s += $2 } END { printf "%.1f", s }' "$2"; }
[ -f "$out/reference.exr" ] || "$bin" render "$scene" "${common[@]}" --method reference --spp 4096 --out "$out/reference.exr" 2>/dev/null
echo "### A. Light maps: \`all\` against the path-traced reference (4096 spp)"
echo
echo "| map | faces × res² | VPL slots | map GPU ms | \`all\` GPU ms | relMSE vs reference | mean ratio |"
echo "|---|---:|---:|---:|---:|---:|---:|"
for spec in "dprsm 128" "cube 128" "rsm 128" "cube 74" "rsm 181"; do
  set -- $spec
  map=$1; res=$2
  case $map in dprsm) faces=2;; cube) faces=6;; rsm) faces=1;; esac
  "$bin" render "$scene" "${common[@]}" --method all --light-map "$map" --dprsm-res "$res" --timings \
    --out "$out/all-$map-$res.exr" > "$out/all-$map-$res.txt" 2>/dev/null
  m=$("$bin" compare "$out/all-$map-$res.exr" "$out/reference.exr" --json)
  printf '| %s | %d × %d² | %d | %s | %s | %.4f | %.4f |\n' "$map" "$faces" "$res" $((faces * res * res)) \
    "$(pass_ms dprsm "$out/all-$map-$res.txt")" "$(pass_ms total "$out/all-$map-$res.txt")" \
    "$(echo "$m" | field rel_mse)" "$(echo "$m" | field mean_ratio)"
done
echo
echo "### B. Per-VPL paraboloid shadow maps (64 shared VPLs, gbg, DPRSM 128²)"
echo
vis=(--method gbg --vpls 64 --dprsm-res 128)
"$bin" render "$scene" "${common[@]}" --method all --visibility exact --dprsm-res 128 --out "$out/all-exact.exr" 2>/dev/null
echo "| visibility | maps memory | psm passes GPU ms | frame GPU ms | relMSE vs \`all\` (exact) |"
echo "|---|---:|---:|---:|---:|"
for res in 64 128 256 512; do
  "$bin" render "$scene" "${common[@]}" "${vis[@]}" --visibility psm --psm-res "$res" --timings \
    --out "$out/psm-$res.exr" > "$out/psm-$res.txt" 2>/dev/null
  b=$("$bin" compare "$out/psm-$res.exr" "$out/all-exact.exr" --json | field rel_mse)
  printf '| psm %d² | %d MiB | %s | %s | %.4f |\n' "$res" $((64 * res * res * 4 / 1048576)) \
    "$(awk '$1 == "psm" || $1 == "psm_select" { s += $2 } END { printf "%.1f", s }' "$out/psm-$res.txt")" \
    "$(pass_ms total "$out/psm-$res.txt")" "$b"
done
for v in voxel exact; do
  "$bin" render "$scene" "${common[@]}" "${vis[@]}" --visibility "$v" --timings --out "$out/pp-$v.exr" > "$out/pp-$v.txt" 2>/dev/null
  b=$("$bin" compare "$out/pp-$v.exr" "$out/all-exact.exr" --json | field rel_mse)
  printf '| %s, per-pixel draws | – | – | %s | %.4f |\n' "$v" "$(pass_ms total "$out/pp-$v.txt")" "$b"
done
for v in psm voxel exact; do
  "$bin" render "$scene" "${common[@]}" --method mis --vpls 64 --dprsm-res 128 --visibility "$v" --timings \
    --out "$out/mis-$v.exr" > "$out/mis-$v.txt" 2>/dev/null
  b=$("$bin" compare "$out/mis-$v.exr" "$out/all-exact.exr" --json | field rel_mse)
  printf '| mis, %s | – | – | %s | %.4f |\n' "$v" "$(pass_ms total "$out/mis-$v.txt")" "$b"
done
