#!/usr/bin/env bash
# Fuzz the scene loader (TOML, OBJ, MTL, PNG) with cargo-fuzz / libFuzzer for a while; the contract it
# checks is in tests/oracles/src/scene_fuzz.rs. Usage: scripts/fuzz.sh [seconds, default 300].
# Needs a nightly toolchain (installed by rustup if missing) and cargo-fuzz (installed if missing).
# New corpus entries go to $CARGO_TARGET_DIR/fuzz-corpus (the committed seeds stay small), crashes to
# $CARGO_TARGET_DIR/fuzz-artifacts; copy a crash into tests/fuzz/regressions/ once fixed, and the
# stable test suite replays it forever (tests/tests/fuzz_corpus.rs).
set -euo pipefail
cd "$(dirname "$0")/.."
secs="${1:-300}"
main_target="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
rustup toolchain list | grep -q '^nightly' || rustup toolchain install nightly --profile minimal
command -v cargo-fuzz >/dev/null || cargo install cargo-fuzz --locked
export CARGO_TARGET_DIR="$main_target/fuzz"
work="$main_target/fuzz-corpus"
mkdir -p "$work" "$main_target/fuzz-artifacts"
cargo +nightly fuzz run --fuzz-dir tests/fuzz scene "$work" tests/fuzz/corpus/scene -- \
  -dict=tests/fuzz/scene.dict -max_total_time="$secs" -max_len=65536 -timeout=10 \
  -artifact_prefix="$main_target/fuzz-artifacts/"
