#!/usr/bin/env bash
# the gain of stratified (Owen-scrambled Sobol) sampling per method at equal VPL count.
# Renders every sampled method with two builds of `bounce` (before and after the change) on the Cornell box
# and two rooms at 64², indirect component, 16 and 64 VPLs, seeds 1..SEEDS, and prints each build's median
# relMSE against `--method all` (rendered once per scene with the second build and kept in the output
# dir: `all` draws nothing, so both builds agree on it) and the ratio before/after as a Markdown table.
# `all` at the default DPRSM resolution takes minutes per scene on lavapipe; a kept all-<scene>.exr is reused.
# Usage: lab/bench-strat.sh <bounce before> <bounce after> [output dir]
#        (SEEDS, default 8; SCENES, default "cornell-box two-rooms")
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
before="$1"
after="$2"
out="${3:-${CARGO_TARGET_DIR:-target}/bench-strat}"
seeds="${SEEDS:-8}"
mkdir -p "$out"
common=(--width 64 --height 64 --component indirect)
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
# Median relMSE of `bin` over the seeds for one scene, method and VPL count: the errors are heavy-tailed
# (a rarely drawn VPL next to x), so a mean of a few seeds is ruled by one outlier.
median_rel_mse() {
  local bin="$1" tag="$2" scene="$3" name="$4" m="$5" n="$6"
  for seed in $(seq 1 "$seeds"); do
    local img="$out/$name-$tag-$m-$n-$seed.exr"
    "$bin" render "$scene" "${common[@]}" --method "$m" --vpls "$n" --seed "$seed" --out "$img" >/dev/null 2>&1
    "$bin" compare "$img" "$out/all-$name.exr" --json | field rel_mse
  done | sort -g | awk '{ v[NR] = $1 } END { printf "%.4g", NR % 2 ? v[(NR + 1) / 2] : (v[NR / 2] + v[NR / 2 + 1]) / 2 }'
}
for name in ${SCENES:-cornell-box two-rooms}; do
  scene="$here/assets/$name/scene.toml"
  [ -f "$out/all-$name.exr" ] || "$after" render "$scene" "${common[@]}" --method all --out "$out/all-$name.exr" >/dev/null 2>&1
  echo
  echo "$name, 64², median relMSE against all over $seeds seeds (before → after, gain = before/after)"
  echo
  echo "| method | 16 VPLs: before | after | gain | 64 VPLs: before | after | gain |"
  echo "|---|---:|---:|---:|---:|---:|---:|"
  for m in uniform global stratified local gbg mis; do
    row="| $m"
    for n in 16 64; do
      b=$(median_rel_mse "$before" before "$scene" "$name" "$m" "$n")
      a=$(median_rel_mse "$after" after "$scene" "$name" "$m" "$n")
      row="$row | $b | $a | $(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.2f", b / a }')×"
    done
    echo "$row |"
  done
done
