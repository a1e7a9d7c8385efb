#!/usr/bin/env bash
# Issue-14 benchmark: the gain of stratified (Owen-scrambled Sobol) sampling per method at equal VPL count.
# Renders every sampled method with two builds of `bounce` (before and after the change) on the Cornell box
# and two rooms at 64², indirect component, 16 and 64 VPLs, seeds 1..SEEDS, and prints each build's mean
# relMSE against `--method all` (rendered once per scene with the second build and kept in the output
# dir: `all` draws nothing, so both builds agree on it) and the ratio before/after as a Markdown table.
# Usage: scripts/bench-strat.sh <bounce before> <bounce after> [output dir]   (SEEDS, default 4)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
before="$1"
after="$2"
out="${3:-${CARGO_TARGET_DIR:-target}/bench-strat}"
seeds="${SEEDS:-4}"
mkdir -p "$out"
common=(--width 64 --height 64 --component indirect)
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
# Mean relMSE of `bin` over the seeds for one scene, method and VPL count.
mean_rel_mse() {
  local bin="$1" tag="$2" scene="$3" name="$4" m="$5" n="$6" sum=0 r
  for seed in $(seq 1 "$seeds"); do
    local img="$out/$name-$tag-$m-$n-$seed.exr"
    "$bin" render "$scene" "${common[@]}" --method "$m" --vpls "$n" --seed "$seed" --out "$img" >/dev/null 2>&1
    r=$("$bin" compare "$img" "$out/all-$name.exr" --json | field rel_mse)
    sum=$(awk -v a="$sum" -v b="$r" 'BEGIN { print a + b }')
  done
  awk -v a="$sum" -v k="$seeds" 'BEGIN { printf "%.4g", a / k }'
}
for name in cornell-box two-rooms; do
  scene="$here/assets/$name/scene.toml"
  [ -f "$out/all-$name.exr" ] || "$after" render "$scene" "${common[@]}" --method all --out "$out/all-$name.exr" >/dev/null 2>&1
  echo
  echo "$name, 64², relMSE against all, mean of $seeds seeds (before → after, gain = before/after)"
  echo
  echo "| method | 16 VPLs: before | after | gain | 64 VPLs: before | after | gain |"
  echo "|---|---:|---:|---:|---:|---:|---:|"
  for m in uniform global stratified local gbg mis; do
    row="| $m"
    for n in 16 64; do
      b=$(mean_rel_mse "$before" before "$scene" "$name" "$m" "$n")
      a=$(mean_rel_mse "$after" after "$scene" "$name" "$m" "$n")
      row="$row | $b | $a | $(awk -v a="$a" -v b="$b" 'BEGIN { printf "%.2f", b / a }')×"
    done
    echo "$row |"
  done
done
