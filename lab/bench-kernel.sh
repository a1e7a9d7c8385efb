#!/usr/bin/env bash
# The VPL kernel (--vpl-kernel point|patch) against the exact one-bounce image (the GPU path tracer,
# `--method reference`), indirect component. Two tables, in Markdown:
#  1. the converged VPL sum (`all`, exact visibility) at 32² pixels, DPRSM 32² and 64² per face, on the
#     Cornell box and the two rooms: relMSE and mean ratio against a 4096-spp reference;
#  2. ris's progressive mean over a long run (64², --vpls 16, SECONDS each, default 40) on Sibenik and
#     Conference at the default DPRSM 512²: what each kernel converges to, and its error there.
# Usage: lab/bench-kernel.sh [output dir] [seconds]   (CARGO_TARGET_DIR is honoured)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-kernel}"
secs="${2:-40}"
mkdir -p "$out"
cargo build -q -p bounce
bin="${CARGO_TARGET_DIR:-target}/debug/bounce"
field() { sed -E "s/.*\"$1\": ([^,}]+).*/\1/"; }
cell() { local m; m=$("$bin" compare "$1" "$2" --json); printf '%.3g / %.4f' "$(echo "$m" | field rel_mse)" "$(echo "$m" | field mean_ratio)"; }
echo "| scene | DPRSM per face | point: relMSE / mean ratio | patch: relMSE / mean ratio |"
echo "|---|---:|---:|---:|"
for s in cornell-box two-rooms; do
  small=(--width 32 --height 32 --component indirect)
  "$bin" render "assets/$s/scene.toml" "${small[@]}" --method reference --spp 4096 --out "$out/$s-ref32.exr" >/dev/null 2>&1
  for res in 32 64; do
    row="| $s | $res² |"
    for k in point patch; do
      "$bin" render "assets/$s/scene.toml" "${small[@]}" --method all --dprsm-res "$res" --vpl-kernel "$k" \
        --out "$out/$s-all-$res-$k.exr" >/dev/null 2>&1
      row="$row $(cell "$out/$s-all-$res-$k.exr" "$out/$s-ref32.exr") |"
    done
    echo "$row"
  done
done
echo
echo "| scene | kernel | frames in ${secs} s | relMSE | mean ratio |"
echo "|---|---|---:|---:|---:|"
for s in sibenik conference; do
  mid=(--width 64 --height 64 --component indirect)
  "$bin" render "assets/$s/scene.toml" "${mid[@]}" --method reference --spp 4096 --out "$out/$s-ref64.exr" >/dev/null 2>&1
  for k in point patch; do
    frames=$("$bin" render "assets/$s/scene.toml" "${mid[@]}" --method ris --vpls 16 --vpl-kernel "$k" \
      --time-limit "$secs" --out "$out/$s-ris-$k.exr" 2>&1 | grep -Eo '^[0-9]+ frame' | grep -Eo '[0-9]+')
    m=$("$bin" compare "$out/$s-ris-$k.exr" "$out/$s-ref64.exr" --json)
    printf '| %s | %s | %s | %.3g | %.4f |\n' "$s" "$k" "$frames" "$(echo "$m" | field rel_mse)" "$(echo "$m" | field mean_ratio)"
  done
done
