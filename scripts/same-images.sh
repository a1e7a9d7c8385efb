#!/usr/bin/env bash
# Shows that this checkout renders exactly what commit BASE rendered: every method, component, light
# map and visibility mode, and ris's features, on the suite's scenes (SCENES, default: all seven),
# compared pixel for pixel (f32 bits). Builds BASE in a temporary git worktree with its own target directory (seeded from this one,
# so shaderc is not compiled twice), renders the same matrix with both binaries at 24², and exits 1
# if any image differs.
#
#   scripts/same-images.sh BASE [OUT_DIR]      e.g.  scripts/same-images.sh 967da6d
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
base="${1:?usage: scripts/same-images.sh BASE [OUT_DIR]}"
out="${2:-$here/target/same-images}"
source "$here/scripts/setup.sh"
cd "$here"
target="${CARGO_TARGET_DIR:-$here/target}"
base_target="$target-base"
work="$(mktemp -d)"
cleanup() { git -C "$here" worktree remove --force "$work/base" >/dev/null 2>&1 || true; rm -rf "$work"; }
trap cleanup EXIT

git worktree add --detach "$work/base" "$base" >/dev/null
if [ ! -d "$base_target" ] && [ -d "$target" ]; then cp -a "$target" "$base_target"; fi
echo "building $base and this checkout..." >&2
# Both with the `lab` feature's switches where the commit has the feature (ris's reuse and pool cases).
CARGO_TARGET_DIR="$base_target" cargo build -q --manifest-path "$work/base/Cargo.toml" -p bounce --features lab 2>/dev/null ||
  CARGO_TARGET_DIR="$base_target" cargo build -q --manifest-path "$work/base/Cargo.toml" -p bounce
cargo build -q -p bounce-tests --bin same-pixels
cargo build -q -p bounce --features lab
# Copies, so that a build during the renders changes neither side.
cp "$target/debug/bounce" "$work/new-bounce"
cp "$base_target/debug/bounce" "$work/old-bounce"
cp "$target/debug/same-pixels" "$work/same-pixels"
new_bin="$work/new-bounce"
old_bin="$work/old-bounce"
same="$work/same-pixels"

common=(--width 24 --height 24 --dprsm-res 16 --voxels 32 --vpls 8 --seed 3 --psm-res 32)
cases=(
  "direct|--component direct"
  "combined-uniform|--component combined --method uniform"
  "combined-all|--component combined --method all"
  "combined-mis|--component combined --method mis"
  "combined-reference|--component combined --method reference --spp 8"
)
for m in uniform all global stratified local gbg mis; do cases+=("indirect-$m|--component indirect --method $m"); done
cases+=(
  "indirect-reference|--component indirect --method reference --spp 16"
  "face-uniform-global|--component indirect --method global --face uniform"
  "thesis-weights-mis|--component indirect --method mis --mis-weights thesis"
  "clamp-uniform|--component indirect --method uniform --clamp 0.01"
  "cdf-seed-gbg|--component indirect --method gbg --cdf-seed 9"
  "regions-local|--component indirect --method local --regions 9"
)
for m in uniform all gbg mis; do cases+=("exact-$m|--component indirect --method $m --visibility exact"); done
for m in uniform global mis; do cases+=("psm-$m|--component indirect --method $m --visibility psm"); done
# ris, the default method, with its features.
cases+=(
  "indirect-ris|--component indirect --method ris"
  "combined-ris|--component combined --method ris"
  "ris-voxel|--component indirect --method ris --visibility voxel"
  "ris-gbg-source|--component indirect --method ris --source gbg"
  "ris-per-pixel|--component indirect --method ris --pool-tiles 0"
  "ris-picks|--component indirect --method ris --picks 3"
  "ris-learned|--component indirect --method ris --learn-visibility 0.1"
  "ris-spatial|--component indirect --method ris --spatial-passes 2"
)
for m in uniform all gbg mis; do cases+=("rsm-$m|--component indirect --method $m --light-map rsm"); done
for m in uniform gbg; do cases+=("cube-$m|--component indirect --method $m --light-map cube"); done

mkdir -p "$out"
fail=0
n=0
for scene in ${SCENES:-cornell-box two-rooms box-on-floor doorway clutter sibenik conference}; do
  for c in "${cases[@]}"; do
    name="${c%%|*}"
    read -r -a flags <<<"${c#*|}"
    for side in old new; do
      bin="$old_bin"; [ "$side" = new ] && bin="$new_bin"
      "$bin" render "assets/$scene/scene.toml" "${common[@]}" "${flags[@]}" \
        --out "$out/$scene-$name.$side.exr" >/dev/null 2>"$out/$scene-$name.$side.log" \
        || { echo "FAIL $scene $name: $side render failed: $(tail -n 1 "$out/$scene-$name.$side.log")"; fail=1; continue 2; }
    done
    n=$((n + 1))
    if diff_msg="$("$same" "$out/$scene-$name.old.exr" "$out/$scene-$name.new.exr")"; then
      echo "same  $scene $name"
    else
      echo "DIFF  $scene $name: $diff_msg"
      fail=1
    fi
  done
done
echo "$n image pairs compared against $base; $( [ $fail = 0 ] && echo 'all bit-identical' || echo 'differences above')"
exit $fail
