#!/usr/bin/env bash
# The real-time frame against per-frame ris under motion: for Sibenik and the two rooms, a camera walk
# (assets/<scene>/camera-path.toml) and, separately, a light orbit, 24 frames each at 128²; ris at 4 and
# at 64 reservoirs a frame (the product's default) and realtime, each frame against its own path-traced
# ground truth (cached in the output folders). Prints one Markdown row per scene, motion and method:
# GPU ms a frame, shadow rays per pixel, relMSE and flicker of the raw estimate and of the denoised one,
# and the raw estimate's efficiency 1 / (relMSE × raw GPU ms) over ris's at 64 (raw GPU ms: the frame less
# the denoiser's passes, what `--denoise off` costs; ris has none).
# Usage: lab/bench-realtime.sh [output dir]   (CARGO_TARGET_DIR is honoured; BOUNCE=path/to/bounce
# measures that build instead of building this tree; REFERENCE_SPP=1 times the same runs against 1-spp
# truths in minutes, whose errors are not to be used: the table's GPU ms)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
out="${1:-${CARGO_TARGET_DIR:-target}/bench-realtime}"
if [ -z "${BOUNCE:-}" ]; then cargo build -q -p bounce; fi
bin="${BOUNCE:-${CARGO_TARGET_DIR:-target}/debug/bounce}"
common=(--frames 24 --width 128 --height 128 --temporal coherent --reference-spp "${REFERENCE_SPP:-1024}")
# The `mean` row of bench.csv: method,temporal,mean,gpu_ms,rays,rel_mse,flicker,denoised_rel_mse,denoised_flicker,raw_gpu_ms
mean_row() { awk -F, -v m="$1" '$1 == m && $3 == "mean"' "$2"; }
echo "| scene | motion | method | GPU ms / frame | raw GPU ms | rays / px | relMSE | flicker | denoised relMSE | denoised flicker | efficiency ÷ ris 64 |"
echo "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|"
for scene in sibenik two-rooms; do
  for motion in camera light; do
    dir="$out/$scene-$motion"
    case "$motion" in
      camera) move=(--animate none --camera-path "assets/$scene/camera-path.toml") ;;
      light) move=(--animate orbit) ;;
    esac
    mkdir -p "$dir/ris64" "$dir/ris4" "$dir/realtime"
    for run in ris64:ris:64 ris4:ris:4 realtime:realtime:1; do
      IFS=: read -r name method vpls <<<"$run"
      # One folder of ground truth for all three runs.
      cp -n "$dir"/ris64/reference-*.exr "$dir/$name/" 2>/dev/null || true
      "$bin" bench "assets/$scene/scene.toml" "${move[@]}" "${common[@]}" --methods "$method" --vpls "$vpls" \
        --out "$dir/$name" >/dev/null 2>&1
      [ "$name" = ris64 ] && for d in ris4 realtime; do cp -n "$dir"/ris64/reference-*.exr "$dir/$d/"; done
    done
    base="$(mean_row ris "$dir/ris64/bench.csv")"
    base_eff="$(echo "$base" | awk -F, '{print 1 / ($6 * $10)}')"
    for run in ris64:ris ris4:ris realtime:realtime; do
      IFS=: read -r name method <<<"$run"
      mean_row "$method" "$dir/$name/bench.csv" | awk -F, -v s="$scene" -v mo="$motion" -v n="$name" -v b="$base_eff" \
        '{d = ($8 == "" ? "–" : sprintf("%.4f", $8)); f = ($9 == "" ? "–" : sprintf("%.4f", $9));
          r = ($5 == "NaN" ? "–" : sprintf("%.2f", $5));
          printf "| %s | %s | %s | %.1f | %.1f | %s | %.4f | %.4f | %s | %s | %.2f |\n", s, mo, n, $4, $10, r, $6, $7, d, f,
            1 / ($6 * $10) / b}'
    done
  done
done
