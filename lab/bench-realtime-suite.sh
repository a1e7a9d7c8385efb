#!/usr/bin/env bash
# The real-time frame on the generated suite: for every scene folder under SCENES (scripts/make-scenes.py),
# a light path (its light-path.toml, else an orbit) and, separately, a camera orbit, FRAMES frames at SIZE², realtime against per-frame ris at
# 4 reservoirs (about twice realtime's shadow rays), each frame against its own path-traced ground truth
# (cached in the output folders; REFS=dir copies them from an earlier run of the same size and frames).
# Prints one Markdown row per scene and motion, then the aggregate over all runs: the geometric mean and
# the worst case of realtime's raw relMSE, raw efficiency 1 / (relMSE × GPU ms) and denoised relMSE over
# ris at 4's raw ones, and of its raw and denoised flicker over ris's.
# Usage: lab/bench-realtime-suite.sh SCENES OUT   (BOUNCE=path/to/bounce measures that build; SIZE=64,
# FRAMES=16 by default; ONLY=realtime runs realtime alone and reads ris's rows from REFS's run)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
scenes="$1"
out="$2"
size="${SIZE:-64}"
frames="${FRAMES:-16}"
if [ -z "${BOUNCE:-}" ]; then (cd "$here" && cargo build -q -p bounce); fi
bin="${BOUNCE:-${CARGO_TARGET_DIR:-$here/target}/debug/bounce}"
methods=ris,realtime
[ "${ONLY:-}" = realtime ] && methods=realtime
# The `mean` row of bench.csv: method,temporal,mean,gpu_ms,rays,rel_mse,flicker,denoised_rel_mse,denoised_flicker,raw_gpu_ms
# (its first ten fields: the rows below index them).
mean_row() { awk -F, -v m="$1" '$1 == m && $3 == "mean"' "$2" | cut -d, -f1-10; }
rows="$out/rows.csv"
mkdir -p "$out"
: >"$rows"
for scene_dir in "$scenes"/*/; do
  scene="$(basename "$scene_dir")"
  for motion in light camera; do
    case "$motion" in
      # The scene's own light path where it has one (make-scenes.py writes one that keeps each light in
      # its room and place: an orbit takes a light by a wall through it, and the run goes dark).
      light) if [ -f "$scene_dir/light-path.toml" ]; then move=(--animate "$scene_dir/light-path.toml"); else move=(--animate orbit); fi ;;
      camera) move=(--animate none --camera-path orbit) ;;
    esac
    dir="$out/$scene-$motion"
    mkdir -p "$dir"
    if [ -n "${REFS:-}" ]; then cp -n "$REFS/$scene-$motion"/reference-*.exr "$dir/" 2>/dev/null || true; fi
    "$bin" bench "$scene_dir/scene.toml" "${move[@]}" --frames "$frames" --width "$size" --height "$size" \
      --temporal coherent --methods "$methods" --vpls 4 --out "$dir" >/dev/null 2>"$dir/stderr" ||
      { echo "error: $scene $motion failed (see $dir/stderr)" >&2; exit 1; }
    ris_csv="$dir/bench.csv"
    [ "${ONLY:-}" = realtime ] && ris_csv="$REFS/$scene-$motion/bench.csv"
    ris="$(mean_row ris "$ris_csv")"
    rt="$(mean_row realtime "$dir/bench.csv")"
    echo "$scene,$motion,$ris,$rt" >>"$rows"
  done
done
# rows.csv: scene,motion, then ris's ($3..$12) and realtime's ($13..$22) mean rows (10 fields each). The raw
# efficiency takes the raw estimate's GPU time (realtime's frame less its denoiser's passes).
echo "| scene | motion | ris 4 ms | ris 4 relMSE | realtime ms | raw ms | relMSE | denoised | flicker ÷ ris | raw efficiency ÷ ris |"
echo "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
awk -F, '{printf "| %s | %s | %.1f | %.4f | %.1f | %.1f | %.4f | %.4f | %.2f | %.2f |\n", $1, $2, $6, $8, $16, $22, $18, $20,
  $19 / $9, ($8 * $12) / ($18 * $22)}' "$rows"
awk -F, '
  function agg(name, v, n,   i, s, w) { s = 0; w = v[1]; for (i = 1; i <= n; i++) { s += log(v[i]); if (v[i] > w) w = v[i] }
    printf "| %s | %.3f | %.3f |\n", name, exp(s / n), w }
  { n++; raw[n] = $18 / $8; eff[n] = ($18 * $22) / ($8 * $12); den[n] = $20 / $8; fl[n] = $19 / $9; dfl[n] = $21 / $9 }
  END {
    print ""; print "| realtime over ris at 4, " n " runs | geometric mean | worst |"; print "|---|---:|---:|"
    agg("raw relMSE", raw, n); agg("relMSE × raw GPU ms (1 / efficiency)", eff, n); agg("denoised relMSE", den, n)
    agg("raw flicker", fl, n); agg("denoised flicker", dfl, n)
  }' "$rows"
