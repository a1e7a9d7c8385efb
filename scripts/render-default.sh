#!/usr/bin/env bash
# Renders the default scene (assets/cornell-box) to cornell.exr and cornell.png in the current
# directory, installing what is missing first: the best image bounce makes in 2 s of frames
# (`--time-limit 2` without --method: the path tracer, BENCHMARKS.md). Extra arguments go to
# `bounce render` (`--method ris` for the VPL estimate in the same time).
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
source "$here/scripts/setup.sh"
cd "$here"
if first_build_notice; then cargo build -p bounce; fi
cargo run -q -p bounce -- render assets/cornell-box/scene.toml --out "${OLDPWD:-.}/cornell.exr" --png "${OLDPWD:-.}/cornell.png" --validation --timings --time-limit 2 "$@"
