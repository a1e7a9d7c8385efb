#!/usr/bin/env bash
# How far the real-time frame's raw error is from the least that two shadow rays drawn by the unshadowed
# contribution can reach, on a still view of Sibenik and of the two rooms (128², light maps 128² a face,
# the indirect component, one VPL set): renders `all` (t), the unshadowed `all` (F, a build with
# lab/unshadowed-all.patch, applied for that build and taken off again), ris at 64 and 8 raw
# realtime frames, then `visibility-floor` prints the floor t (F − t) / k for k = 1, 2 and 64 rays
# and each image's relMSE against `all` (BENCHMARKS.md, "Real time under motion").
# Usage: lab/bench-visibility-floor.sh [output dir]   (CARGO_TARGET_DIR is honoured; needs
# glsl/gather.comp as committed)
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
cd "$here"
target="${CARGO_TARGET_DIR:-target}"
out="${1:-$target/bench-visibility-floor}"
mkdir -p "$out"
if ! git diff --quiet -- glsl/gather.comp; then
  echo "error: glsl/gather.comp has changes: commit or stash them first" >&2
  exit 1
fi
cargo build -q --release -p bounce -p bounce-lab
cp "$target/release/bounce" "$out/bounce"
git apply lab/unshadowed-all.patch
trap 'git apply -R lab/unshadowed-all.patch' EXIT
cargo build -q --release -p bounce
cp "$target/release/bounce" "$out/bounce-unshadowed"
git apply -R lab/unshadowed-all.patch
trap - EXIT
cargo build -q --release -p bounce
trap 'echo "error: a step failed (the renders log to $out/SCENE/log)" >&2' ERR
common=(--component indirect --width 128 --height 128 --dprsm-res 128 --cdf-seed 1)
for scene in sibenik two-rooms; do
  d="$out/$scene"
  mkdir -p "$d"
  s="assets/$scene/scene.toml"
  "$out/bounce" render "$s" --method all "${common[@]}" --out "$d/all.exr" >/dev/null 2>>"$d/log"
  "$out/bounce-unshadowed" render "$s" --method all "${common[@]}" --out "$d/unshadowed.exr" >/dev/null 2>>"$d/log"
  "$out/bounce" render "$s" --method ris --vpls 64 "${common[@]}" --out "$d/ris64.exr" >/dev/null 2>>"$d/log"
  "$out/bounce" render "$s" --method realtime --denoise off --frames 8 "${common[@]}" --out-dir "$d/realtime" >/dev/null 2>>"$d/log"
  echo "## $scene"
  "$target/release/visibility-floor" "$d/all.exr" "$d/unshadowed.exr" "$d/ris64.exr" \
    "$d"/realtime/frame_000{0,3,7}.exr
done
