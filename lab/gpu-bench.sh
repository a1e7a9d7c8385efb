#!/usr/bin/env bash
# The thesis's measurements on a machine with a GPU, prepared here and run there in one command.
#
#   lab/gpu-bench.sh stage          # here: build (release), then stage the stripped binary and the
#                                       # Vulkan loader under out/gpu-bench/ (ignored by git; ~12 MiB)
#   lab/gpu-bench.sh run [OUT_DIR]  # there, from the repository root (assets/ and out/gpu-bench/
#                                       # present): ~6 minutes on a recent GPU
#   lab/gpu-bench.sh tiny [OUT_DIR] # the same steps at a tiny size on whatever device is here
#                                       # (lavapipe in CI): builds (debug), stages and runs (~3 minutes)
#
# A/B comparisons of builds, for the few minutes a GPU is lent (one command there for all of them):
#   lab/gpu-bench.sh stage-ab LABEL # here: build (release) the working tree as it is now and keep
#                                       # it as out/gpu-bench/ab/LABEL.gz (~4 MiB: ten builds travel)
#   lab/gpu-bench.sh stage-experiments  # here, in a clean working tree: stage-ab it as `head` and,
#                                       # for each lab/experiments/*.patch that applies, the tree with
#                                       # that patch as the patch's name (each applied, built, reverted)
#   lab/gpu-bench.sh ab OUT_DIR [LABEL…]  # there: each build's gather GPU ms (median of 3 after a
#                                       # warm-up process) per scene and size, the first build's voxel
#                                       # march beside them, and whether each build's image equals the
#                                       # first's; AB_SCENES, AB_SIZES, AB_METHOD, AB_VPLS, AB_VISIBILITY
#                                       # choose (defaults: 4 scenes, 512 and 1024, uniform, 256, exact)
#   lab/gpu-bench.sh rt-ab OUT_DIR LABEL…  # there: each build's real-time frame at 1920×1080 under the
#                                       # camera's path, the light's orbit and both, the raster passes'
#                                       # GPU ms beside the rest's, and whether its frames equal the
#                                       # first build's; RT_SCENES, RT_SIZE, RT_FRAMES and RT_DPRSM
#                                       # choose (sibenik conference, 1920x1080, 24, 512)
#
# `run` prints, most important first, each part appended to OUT_DIR/gpu-bench.md as soon as it is done:
# (0) the real-time frame (`--method realtime`) at 1920×1080 on Sibenik and Conference while the camera
# walks and the light orbits, each pass's GPU ms (the goal on an H200: at most 8 ms a frame), at `render`'s
# map sizes and at the viewer's; (1) the gather's GPU ms by visibility (voxel, exact, and the end balls' own passes) on every scene of
# the suite at 256 VPLs per pixel, median of 3 frames (the cost bound: the default visibility's gather
# no dearer than the voxel march's), at 512² and at the 64² of the lavapipe tables;
# (2) for Sibenik and Conference the thesis configuration (512², 800 VPLs per pixel; global, local, gbg,
# mis, ris; the indirect component) with each pass's GPU ms, median of 3 frames with the kept products
# dropped before each (full frames), shaped like the thesis's Tables 7.1 and 7.2; (3) the equal-time
# error of each method against the path-traced ground truth (`--method reference`), every method given
# the same wall-time budget (`render --time-limit`). No validation layers there (a GPU machine may have
# none).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
mode="${1:-}"
stage="$here/out/gpu-bench"

# $1: the cargo profile (release for a GPU's timings; debug for the tiny run, which CI's cache holds).
stage_binary() {
  local profile="$1"
  source "$here/scripts/setup.sh"
  (cd "$here" && cargo build -q -p bounce --profile "$profile")
  local target="${CARGO_TARGET_DIR:-$here/target}"
  local dir="$profile"
  [ "$profile" = dev ] && dir=debug
  mkdir -p "$stage/bin" "$stage/lib"
  cp "$target/$dir/bounce" "$stage/bin/bounce.tmp"
  strip "$stage/bin/bounce.tmp" 2>/dev/null || true
  mv "$stage/bin/bounce.tmp" "$stage/bin/bounce"
  # The loader, for a machine that has a GPU driver but no libvulkan; and glvnd's dispatch libraries,
  # without which NVIDIA's driver (libGLX_nvidia) loads but hands the loader no vkCreateInstance
  # ("incompatible driver": an H200 machine, 2026-12-04).
  local lib path
  for lib in libvulkan.so.1 libGLdispatch.so.0 libGLX.so.0 libEGL.so.1 libOpenGL.so.0; do
    path="$(ldconfig -p | awk -v l="$lib" '$1 == l && !n++ {print $NF}')"
    [ -n "$path" ] && cp -L "$path" "$stage/lib/$lib"
  done
  echo "staged $(du -sh "$stage" | cut -f1) in $stage" >&2
}

median3() { sort -g | sed -n 2p; }

# Use the staged loader, and NVIDIA's driver where its manifest is (a GPU machine without a system loader).
use_staged_loader() {
  export LD_LIBRARY_PATH="$stage/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  local icd=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
  if [ -z "${VK_DRIVER_FILES:-}" ] && [ -f "$icd" ]; then export VK_DRIVER_FILES="$icd"; fi
}

# $1 LABEL, $2 cargo profile: the working tree's build, kept compressed for `ab`.
stage_ab() {
  local label="$1" profile="$2"
  [[ "$label" =~ ^[A-Za-z0-9_.-]+$ ]] || { echo "error: a build label is letters, digits, '.', '_' or '-'" >&2; exit 2; }
  stage_binary "$profile"
  mkdir -p "$stage/ab"
  gzip -9 -c "$stage/bin/bounce" >"$stage/ab/$label.gz.tmp"
  mv "$stage/ab/$label.gz.tmp" "$stage/ab/$label.gz"
  echo "staged build $label in $stage/ab/$label.gz" >&2
}

# The working tree as `head`, and with each experiment patch that applies to it (lab/experiments/).
stage_experiments() {
  cd "$here"
  if ! git diff --quiet || ! git diff --cached --quiet; then
    echo "error: stage-experiments applies patches to the working tree: commit or stash its changes first" >&2
    exit 2
  fi
  stage_ab head release
  # Names of their own: stage_ab sources setup.sh, whose loop variable would overwrite a `p`.
  local experiment_patch experiment_label
  for experiment_patch in lab/experiments/*.patch; do
    [ -e "$experiment_patch" ] || continue
    experiment_label="$(basename "$experiment_patch" .patch)"
    if ! git apply --check "$experiment_patch" 2>/dev/null; then
      echo "skipping $experiment_label: it does not apply to this tree (see the first lines of its patch)" >&2
      continue
    fi
    git apply "$experiment_patch"
    # Whatever happens to the build, the patch comes out again.
    trap "git apply -R '$experiment_patch'" EXIT
    stage_ab "$experiment_label" release
    git apply -R "$experiment_patch"
    trap - EXIT
  done
  # `run` uses the staged binary: the head build again, not the last patched one.
  gunzip -c "$stage/ab/head.gz" >"$stage/bin/bounce.tmp"
  chmod +x "$stage/bin/bounce.tmp"
  mv "$stage/bin/bounce.tmp" "$stage/bin/bounce"
  echo "there: lab/gpu-bench.sh ab OUT_DIR (every staged build; AB_SIZES=1024 halves the time)" >&2
}

# $1 OUT_DIR, then the labels (default: every staged build): the real-time frame at RT_SIZE (default
# 1920x1080) on RT_SCENES (default: sibenik conference) under each motion (the camera's path alone, the
# light's orbit alone, both), RT_FRAMES frames (default 24), GPU ms (median over frames 1..) of the
# raster passes, of the rest and in all, and whether the last frame equals the first build's.
# Writes OUT_DIR/rt-ab.md.
run_rt_ab() {
  local out="$1"
  shift
  local labels=("$@")
  [ "${#labels[@]}" -gt 0 ] || { echo "error: usage: lab/gpu-bench.sh rt-ab OUT_DIR LABEL…" >&2; exit 2; }
  use_staged_loader
  mkdir -p "$out/bin"
  local l
  for l in "${labels[@]}"; do
    [ -f "$stage/ab/$l.gz" ] || { echo "error: no staged build '$l' in $stage/ab" >&2; exit 2; }
    gunzip -c "$stage/ab/$l.gz" >"$out/bin/$l"
    chmod +x "$out/bin/$l"
  done
  local size="${RT_SIZE:-1920x1080}" frames="${RT_FRAMES:-24}" scenes
  read -ra scenes <<<"${RT_SCENES:-sibenik conference}"
  local md="$out/rt-ab.md" first="${labels[0]}" last=frame_0002.exr
  {
    echo "# gpu-bench rt-ab: $(date -u +%Y-%m-%d), $("$out/bin/$first" info | sed -n '1s/, Vulkan.*//p')"
    echo
    echo "\`--method realtime\` at $size, DPRSM ${RT_DPRSM:-512}², $frames frames; GPU ms, median over"
    echo "frames 1.., not written; 'rest': the sum of the other passes' medians; '=': frame 2 equals $first's."
    echo
    echo "| scene | motion | build | dprsm | gbuffer | rest | total | rays / px |"
    echo "|---|---|---|---:|---:|---:|---:|---:|"
  } | tee "$md"
  local scene motion
  for scene in "${scenes[@]}"; do
    local toml="$here/assets/$scene/scene.toml"
    for motion in camera light both; do
      local paths=()
      local walk="$here/assets/$scene/camera-path.toml"
      [ -f "$walk" ] || walk=orbit
      [ "$motion" != light ] && paths+=(--camera-path "$walk")
      [ "$motion" != camera ] && paths+=(--light-path orbit)
      for l in "${labels[@]}"; do
        rm -rf "$out/rt-$l"
        local timings common=(--method realtime --width "${size%x*}" --height "${size#*x}" --dprsm-res "${RT_DPRSM:-512}"
          "${paths[@]}")
        # Timed unwritten (frames back to back: written frames idle the GPU and its clocks fall), then
        # three frames written for the comparison.
        timings="$("$out/bin/$l" render "$toml" "${common[@]}" --frames "$frames" --timings 2>/dev/null)" || timings=""
        [ "${#labels[@]}" -gt 1 ] &&
          { "$out/bin/$l" render "$toml" "${common[@]}" --frames 3 --out-dir "$out/rt-$l" >/dev/null 2>&1 || true; }
        local same=""
        if [ "$l" != "$first" ] && [ -f "$out/rt-$l/$last" ] && [ -f "$out/rt-$first/$last" ]; then
          "$out/bin/$first" compare "$out/rt-$l/$last" "$out/rt-$first/$last" --json | grep -q '"rmse": 0,' && same=" ="
        fi
        echo "$timings" | awk -v s="$scene" -v m="$motion" -v l="$l" -v same="$same" '
          $1 == "dprsm" || $1 == "gbuffer" {ms[$1] = $2; next}
          $1 == "total" {total = $2; next}
          NF == 2 && $2 ~ /^-?[0-9.]+$/ {rest += $2}
          $1 == "shadow" {rays = $5}
          END {
            if (total == "") {printf "| %s | %s | %s | – | – | – | failed | – |\n", s, m, l; exit}
            printf "| %s | %s | %s | %s | %s | %.2f | %.2f%s | %s |\n", s, m, l,
              ms["dprsm"] == "" ? "–" : ms["dprsm"],
              ms["gbuffer"] == "" ? "–" : ms["gbuffer"], rest, total, same, rays}' | tee -a "$md"
      done
      for l in "${labels[@]}"; do [ "$l" != "$first" ] && rm -rf "$out/rt-$l"; done
    done
    rm -rf "$out/rt-$first"
  done
  echo "wrote $md" >&2
}

# $1 OUT_DIR, then the labels (default: every staged build). Writes OUT_DIR/ab.md.
run_ab() {
  local out="$1"
  shift
  local labels=("$@")
  if [ "${#labels[@]}" -eq 0 ]; then
    local f
    # `head` (stage-experiments' unpatched build) first: the others are compared with it.
    [ -f "$stage/ab/head.gz" ] && labels+=(head)
    for f in "$stage"/ab/*.gz; do
      [ -e "$f" ] && [ "$(basename "$f" .gz)" != head ] && labels+=("$(basename "$f" .gz)")
    done
  fi
  [ "${#labels[@]}" -gt 0 ] || { echo "error: no build staged: run 'lab/gpu-bench.sh stage-ab LABEL' first" >&2; exit 2; }
  local l
  for l in "${labels[@]}"; do
    [ -f "$stage/ab/$l.gz" ] || { echo "error: no staged build '$l' in $stage/ab" >&2; exit 2; }
  done
  use_staged_loader
  mkdir -p "$out/bin"
  for l in "${labels[@]}"; do
    gunzip -c "$stage/ab/$l.gz" >"$out/bin/$l"
    chmod +x "$out/bin/$l"
  done
  local scenes sizes
  read -ra scenes <<<"${AB_SCENES:-sibenik conference clutter cornell-box}"
  read -ra sizes <<<"${AB_SIZES:-512 1024}"
  local method="${AB_METHOD:-uniform}" vpls="${AB_VPLS:-256}" vis="${AB_VISIBILITY:-exact}"
  local md="$out/ab.md" first="${labels[0]}"
  gather_ms() { # build scene size seed visibility image
    "$out/bin/$1" render "$here/assets/$2/scene.toml" --width "$3" --height "$3" --component indirect \
      --method "$method" --vpls "$vpls" --seed "$4" --visibility "$5" --timings --out "$6" 2>/dev/null |
      awk '$1 == "gather" {print $2}'
  }
  {
    echo "# gpu-bench ab: $(date -u +%Y-%m-%d), $("$out/bin/$first" info | sed -n '1s/, Vulkan.*//p')"
    echo
    echo "Gather GPU ms, \`$method\`, $vpls VPLs per pixel, \`--visibility $vis\` (voxel: $first's march),"
    echo "median of 3 processes (seeds 1–3) after a warm-up one; '=' after a time: the seed-1 image equals $first's."
    echo
    printf '| scene | size | voxel |'; for l in "${labels[@]}"; do printf ' %s |' "$l"; done; echo
    printf '|---|---:|---:|'; for l in "${labels[@]}"; do printf -- '---:|'; done; echo
  } | tee "$md"
  local scene size k
  for scene in "${scenes[@]}"; do
    for size in "${sizes[@]}"; do
      gather_ms "$first" "$scene" "$size" 0 voxel "$out/warm.exr" >/dev/null
      local row voxel
      voxel="$(for k in 1 2 3; do gather_ms "$first" "$scene" "$size" "$k" voxel "$out/voxel.exr"; done | median3)"
      row="| $scene | $size | ${voxel:-–} |"
      for l in "${labels[@]}"; do
        local ms same=""
        ms="$(for k in 1 2 3; do gather_ms "$l" "$scene" "$size" "$k" "$vis" "$out/$l-$k.exr"; done | median3)"
        if [ "$l" != "$first" ] && [ -f "$out/$l-1.exr" ] && [ -f "$out/$first-1.exr" ]; then
          "$out/bin/$first" compare "$out/$l-1.exr" "$out/$first-1.exr" --json | grep -q '"rmse": 0,' && same=" ="
        fi
        row="$row ${ms:-–}$same |"
      done
      echo "$row" | tee -a "$md"
    done
  done
  rm -f "$out"/*.exr
  echo "wrote $md" >&2
}

# The gather's GPU ms by visibility on each scene, `uniform` at $vpls VPLs per pixel, median of 3 frames
# (the cost bound: the default visibility's gather no dearer than the voxel march's).
vis_table() {
  local out="$1" md="$2" size="$3" vpls="$4" dprsm="$5"
  shift 5
  {
    echo
    echo "## Gather GPU ms by visibility (uniform, $vpls VPLs per pixel, ${size}², DPRSM ${dprsm}², median of 3 frames)"
    echo
    echo "| scene | voxel | exact | exact ÷ voxel | end balls |"
    echo "|---|---:|---:|---:|---:|"
  } | tee -a "$md"
  local scene v
  for scene in "$@"; do
    local toml="$here/assets/$scene/scene.toml"
    declare -A ms=()
    # `end balls`: the two passes that make exact's balls, once per G-buffer and VPL set (not part of the
    # gather's ms).
    for v in voxel exact; do
      local args=(--visibility "$v")
      ms[$v]="$(for k in 1 2 3; do "$bin" render "$toml" --width "$size" --height "$size" --component indirect \
        --dprsm-res "$dprsm" --method uniform --vpls "$vpls" --seed "$k" \
        "${args[@]}" --timings --out "$out/vis-$scene-$v.exr" 2>/dev/null | awk '$1 == "gather" {print $2}'; done | median3)"
    done
    ms[balls]="$("$bin" render "$toml" --width "$size" --height "$size" --component indirect --dprsm-res "$dprsm" \
      --method uniform --vpls "$vpls" --visibility exact --timings --out "$out/vis-$scene-balls.exr" \
      2>/dev/null | awk '$1 ~ /^end_balls/ {s += $2} END {if (NR) printf "%.2f", s}')"
    local ratio="–"
    [ -n "${ms[voxel]}" ] && [ -n "${ms[exact]}" ] && ratio="$(awk -v e="${ms[exact]}" -v x="${ms[voxel]}" 'BEGIN {printf "%.2f", e / x}')"
    echo "| $scene | ${ms[voxel]:-–} | ${ms[exact]:-–} | $ratio | ${ms[balls]:-–} |" | tee -a "$md"
    unset ms
  done
}

# The thesis configuration's per-pass GPU ms (Tables 7.1/7.2) for each of $scenes.
pass_tables() {
  local out="$1" md="$2"
  shift 2
  local scene m k p
  for scene in "${scenes[@]}"; do
    local toml="$here/assets/$scene/scene.toml"
    {
      echo
      echo "## $scene: GPU ms per pass (median of 3 full frames; Tables 7.1/7.2)"
      echo
    } | tee -a "$md"
    local table="$out/$scene-passes.txt"
    : >"$table"
    for m in "${methods[@]}"; do
      for k in 1 2 3; do
        "$bin" render "$toml" "${common[@]}" --method "$m" --vpls "$vpls" --seed "$k" --timings \
          --out "$out/$scene-$m-$k.exr" 2>/dev/null | awk -v m="$m" -v k="$k" \
          'NF==2 && $2 ~ /^[0-9.]+$/ {print m, k, $1, $2}' >>"$table"
      done
    done
    local passes
    passes="$(awk '$3 != "total" {print $3}' "$table" | awk '!seen[$0]++' | tr '\n' ' ')total"
    {
      printf '| method |'; for p in $passes; do printf ' %s |' "$p"; done; echo
      printf '|---|'; for p in $passes; do printf -- '---:|'; done; echo
      for m in "${methods[@]}"; do
        printf '| %s |' "$m"
        for p in $passes; do
          v="$(awk -v m="$m" -v p="$p" '$1==m && $3==p {print $4}' "$table" | median3)"
          printf ' %s |' "${v:-–}"
        done
        echo
      done
    } | tee -a "$md"
  done
}

# The real-time frame (`--method realtime`, denoised) at $1 × $2 on each of $scenes while the camera
# walks its path (assets/<scene>/camera-path.toml) and the light orbits: each pass's GPU ms, the median
# over frames 1..$3 (frame 0 builds what the others keep), and the shadow rays per pixel.
realtime_table() {
  local out="$1" md="$2" w="$3" h="$4" frames="$5" dprsm="$6"
  local scene
  for scene in "${scenes[@]}"; do
    local toml="$here/assets/$scene/scene.toml"
    {
      echo
      echo "## $scene: the real-time frame at ${w}×${h}, DPRSM ${dprsm}², camera path and light orbit ($frames frames, unwritten; GPU ms, median over frames 1..)"
      echo
      echo '```text'
      "$bin" render "$toml" --method realtime --width "$w" --height "$h" --dprsm-res "$dprsm" \
        --frames "$frames" --camera-path "$here/assets/$scene/camera-path.toml" --light-path orbit --timings 2>/dev/null
      echo '```'
    } | tee -a "$md"
  done
}

# Each method's error against the path-traced ground truth at equal wall time, for each of $scenes.
equal_time() {
  local out="$1" md="$2"
  local scene m
  for scene in "${scenes[@]}"; do
    local toml="$here/assets/$scene/scene.toml"
    local ref="$out/$scene-reference.exr"
    "$bin" render "$toml" "${common[@]}" --method reference --spp "$spp" --out "$ref" 2>/dev/null
    {
      echo
      echo "## $scene: equal time ($budget s of wall time per method) against the ground truth (reference, $spp spp)"
      echo
      echo "| method | frames | relMSE | mean ratio |"
      echo "|---|---:|---:|---:|"
    } | tee -a "$md"
    for m in uniform "${methods[@]}" reference; do
      local img="$out/$scene-$m-equal-time.exr"
      local per_frame=(--vpls "$vpls")
      [ "$m" = reference ] && per_frame=(--spp 16)
      local log
      log="$("$bin" render "$toml" "${common[@]}" --method "$m" "${per_frame[@]}" --seed 101 \
        --time-limit "$budget" --out "$img" 2>&1 >/dev/null)"
      local frames
      frames="$(echo "$log" | awk '/frame\(s\) in/{print $1}')"
      local json
      json="$("$bin" compare "$img" "$ref" --json)"
      local rel mean
      rel="$(echo "$json" | sed -E 's/.*"rel_mse": ([^,]+),.*/\1/')"
      mean="$(echo "$json" | sed -E 's/.*"mean_ratio": ([^,]+),.*/\1/')"
      printf '| %s | %s | %.4g | %.4f |\n' "$m" "${frames:-?}" "$rel" "$mean" | tee -a "$md"
    done
  done
}

# $1 OUT_DIR; $2 size, $3 VPLs per pixel, $4 DPRSM resolution, $5 reference spp, $6 equal-time budget (s),
# $7 the visibility tables' sizes (comma-separated), $8 the real-time frame's WIDTHxHEIGHT; the rest: scenes of the thesis tables (the visibility tables take every scene of
# the suite).
run_bench() {
  local out="$1" size="$2" vpls="$3" dprsm="$4" spp="$5" budget="$6" vis_sizes="$7" rt_size="$8"
  shift 8
  local scenes=("$@")
  bin="$stage/bin/bounce"
  [ -x "$bin" ] || { echo "error: $bin is missing: run 'lab/gpu-bench.sh stage' first" >&2; exit 2; }
  use_staged_loader
  mkdir -p "$out"
  local md="$out/gpu-bench.md"
  local device
  device="$("$bin" info | sed -n '1s/, Vulkan.*//p')"
  [ -n "$device" ] || { echo "error: no Vulkan device found ('bounce info' printed nothing)" >&2; exit 1; }
  common=(--width "$size" --height "$size" --component indirect --dprsm-res "$dprsm")
  methods=(global local gbg mis ris)
  {
    echo "# gpu-bench: $(date -u +%Y-%m-%d), $device"
    echo
    echo "\`lab/gpu-bench.sh $mode\`: ${size}², ${vpls} VPLs per pixel, DPRSM ${dprsm}² per face, indirect."
  } | tee "$md"
  # The whole suite at 256 VPLs; the tiny run keeps to its own scenes and VPL count.
  local suite=(cornell-box two-rooms box-on-floor doorway clutter sibenik conference) vis_vpls=256
  [ "$mode" = tiny ] && suite=("${scenes[@]}") && vis_vpls="$vpls"
  local vs
  IFS=, read -ra vs <<<"$vis_sizes"
  SECONDS=0
  # The real-time frame first: the 1080p goal (8 ms).
  realtime_table "$out" "$md" "${rt_size%x*}" "${rt_size#*x}" 24 "$dprsm"
  # And at the viewer's map size (half of `render`'s each way), what an interactive user gets.
  realtime_table "$out" "$md" "${rt_size%x*}" "${rt_size#*x}" 24 "$((dprsm / 2))"
  echo "real-time frames: done at ${SECONDS} s" >&2
  vis_table "$out" "$md" "${vs[0]}" "$vis_vpls" "$dprsm" "${suite[@]}"
  echo "visibility table at ${vs[0]}²: done at ${SECONDS} s" >&2
  pass_tables "$out" "$md"
  echo "pass tables: done at ${SECONDS} s" >&2
  equal_time "$out" "$md"
  echo "equal time: done at ${SECONDS} s" >&2
  local s
  for s in "${vs[@]:1}"; do
    vis_table "$out" "$md" "$s" "$vis_vpls" 32 "${suite[@]}"
    echo "visibility table at $s²: done at ${SECONDS} s" >&2
  done
  echo >&2
  echo "wrote $md" >&2
}

case "$mode" in
  stage) stage_binary release ;;
  run) run_bench "${2:-$here/out/gpu-bench-results}" 512 800 512 2048 2 512,64 1920x1080 sibenik conference ;;
  stage-ab)
    [ $# -eq 2 ] || { echo "error: usage: lab/gpu-bench.sh stage-ab LABEL" >&2; exit 2; }
    stage_ab "$2" release
    ;;
  stage-experiments) stage_experiments ;;
  rt-ab)
    [ $# -ge 3 ] || { echo "error: usage: lab/gpu-bench.sh rt-ab OUT_DIR LABEL…" >&2; exit 2; }
    run_rt_ab "${@:2}"
    ;;
  ab)
    [ $# -ge 2 ] || { echo "error: usage: lab/gpu-bench.sh ab OUT_DIR [LABEL…]" >&2; exit 2; }
    run_ab "${@:2}"
    ;;
  tiny)
    # A stage of its own, so that CI's debug build never replaces a staged release build.
    stage="$here/out/gpu-bench-tiny-stage"
    stage_binary dev
    run_bench "${2:-$here/out/gpu-bench-tiny}" 24 8 16 32 0.3 16 32x18 sibenik conference
    # The A/B steps on one build staged under two labels (their images must match).
    stage_ab tiny-a dev
    stage_ab tiny-b dev
    AB_SCENES=cornell-box AB_SIZES=16 AB_VPLS=8 run_ab "${2:-$here/out/gpu-bench-tiny}/ab" tiny-a tiny-b
    RT_SCENES=cornell-box RT_SIZE=32x18 RT_FRAMES=3 RT_DPRSM=16 \
      run_rt_ab "${2:-$here/out/gpu-bench-tiny}/rt-ab" tiny-a tiny-b
    ;;
  *)
    echo "error: usage: lab/gpu-bench.sh stage | run [OUT_DIR] | tiny [OUT_DIR] | stage-ab LABEL | stage-experiments | ab OUT_DIR [LABEL…] | rt-ab OUT_DIR LABEL…" >&2
    exit 2
    ;;
esac
