#!/usr/bin/env bash
# Renders the default scene (assets/cornell-box) to cornell.exr and cornell.png in the current
# directory, installing what is missing first. Extra arguments go to `bounce render`.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
source "$here/scripts/setup.sh"
cd "$here"
if first_build_notice; then cargo build -p bounce; fi
cargo run -q -p bounce -- render assets/cornell-box/scene.toml --out "${OLDPWD:-.}/cornell.exr" --png "${OLDPWD:-.}/cornell.png" --validation --timings "$@"
