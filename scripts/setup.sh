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
