#!/usr/bin/env bash
# Runs the whole test suite on the Vulkan device the loader offers (lavapipe on a machine without a
# GPU) with the validation layers on, installing what is missing first.
set -euo pipefail
here="$(cd "$(dirname "$0")/.." && pwd)"
source "$here/scripts/setup.sh"
cd "$here"
if first_build_notice; then cargo build --workspace --all-targets; fi
# Shape before behaviour: formatting, lints, and the structure rules of ARCHITECTURE.md.
cargo fmt --all --check
cargo clippy -q --workspace --all-targets -- -D warnings
# The A/B switches of the `lab` feature, built once so they keep compiling.
cargo clippy -q -p bounce --features lab -- -D warnings
python3 scripts/check-structure.py
cargo build -q --workspace --all-targets
cargo run -q -p bounce -- info | sed -n 1,3p
# The default scene at 128² with validation: must finish and name every pass it ran.
cargo run -q -p bounce -- render assets/cornell-box/scene.toml --width 128 --height 128 \
  --out "${CARGO_TARGET_DIR:-target}/default-128.exr" --validation --timings
# The GPU benchmark's steps, end to end at a tiny size on this device (lab/gpu-bench.sh): it must run.
./lab/gpu-bench.sh tiny "${CARGO_TARGET_DIR:-target}/gpu-bench-tiny" >/dev/null
log="$(mktemp)"
trap 'rm -f "$log"' EXIT
set +e
cargo test --workspace --all-targets 2>&1 | tee "$log"
status=${PIPESTATUS[0]}
set -e
passed=$(grep -Eo '^test result: .* ([0-9]+) passed' "$log" | grep -Eo '[0-9]+ passed' | awk '{s+=$1} END {print s+0}')
failed=$(grep -Eo '[0-9]+ failed' "$log" | awk '{s+=$1} END {print s+0}')
echo "bounce tests: $passed passed, $failed failed"
exit "$status"
