#!/usr/bin/env bash
# Installs what bounce needs on Debian 12, idempotently: only missing packages are installed.
# Sourced by render-default.sh and test.sh; safe to run on its own.
set -euo pipefail

packages=(
  mesa-vulkan-drivers      # lavapipe, the CPU Vulkan device
  vulkan-validationlayers  # VK_LAYER_KHRONOS_validation (tests and --validation)
  libvulkan1               # the Vulkan loader
  cmake ninja-build g++ python3 git  # the shaderc crate builds glslang/shaderc from source
  xvfb xauth               # `bounce view` tests: a virtual X display (xvfb-run)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if ((${#missing[@]})); then
  echo "installing: ${missing[*]}" >&2
  sudo=""
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
if ! command -v cargo >/dev/null 2>&1; then
  [ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
fi
command -v cargo >/dev/null 2>&1 || { echo "error: cargo not found; install Rust 1.80 or newer (https://rustup.rs)" >&2; exit 1; }

# The first build compiles shaderc (glslang and SPIRV-Tools, C++) from source: say so before it starts,
# and show cargo's progress (the callers build without -q when nothing is built yet).
first_build_notice() {
  local target="${CARGO_TARGET_DIR:-$(pwd)/target}"
  if ! ls "$target"/debug/build/shaderc-sys-*/out >/dev/null 2>&1; then
    echo "first build: compiling shaderc (glslang, SPIRV-Tools) from source; about 12.5 minutes on 2 cores" \
      "(measured 2026-12-03), less with more cores (it builds in parallel). Later builds take seconds." >&2
    return 0
  fi
  return 1
}
