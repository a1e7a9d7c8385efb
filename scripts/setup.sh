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
  libxcursor1 libxi6 libxkbcommon0 libxkbcommon-x11-0  # what winit loads at run time to open a window on X
)

# Installs the packages of "$@" that are missing (as root, or through sudo).
apt_install() {
  local missing=() p sudo=""
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]})) || return 0
  echo "installing: ${missing[*]}" >&2
  [ "$(id -u)" -eq 0 ] || sudo="sudo"
  if [ -n "$sudo" ] && ! command -v sudo >/dev/null 2>&1; then
    echo "error: missing packages (${missing[*]}) and no sudo to install them: run this as root once" >&2
    exit 1
  fi
  $sudo apt-get update -qq
  # env, not a prefix: sudo resets the environment it is given.
  $sudo env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
}
apt_install "${packages[@]}"

# Rust: the oldest the locked dependencies build with (Cargo.toml's rust-version). A missing or older
# toolchain is installed with rustup (Debian's own cargo is too old), with rustfmt and clippy for test.sh;
# a toolchain that is new enough is left as it is.
rust_minimum=1.88
cargo_bin="${CARGO_HOME:-$HOME/.cargo}/bin"
rust_ok() {
  local v
  v="$(rustc --version 2>/dev/null | awk '{print $2}')" || return 1
  [ -n "$v" ] && [ "$(printf '%s\n%s\n' "$rust_minimum" "$v" | sort -V | head -1)" = "$rust_minimum" ]
}
if ! rust_ok && [ -x "$cargo_bin/cargo" ]; then
  export PATH="$cargo_bin:$PATH"
fi
if ! rust_ok; then
  echo "installing Rust (stable, $rust_minimum or newer) with rustup" >&2
  if ! command -v rustup >/dev/null 2>&1; then
    apt_install curl ca-certificates
    curl --proto '=https' --tlsv1.2 -sSf https://sh.rustup.rs | sh -s -- -y -q --profile minimal --no-modify-path
    export PATH="$cargo_bin:$PATH"
    echo "note: Rust is in $cargo_bin; a new shell finds it after \`. ${CARGO_HOME:-$HOME/.cargo}/env\`" >&2
  fi
  rustup -q toolchain install stable --profile minimal --component rustfmt clippy
  rustup -q default stable
fi
rust_ok || { echo "error: Rust $rust_minimum or newer is needed (rustc: $(rustc --version 2>&1))" >&2; exit 1; }
# test.sh checks formatting and lints: a minimal toolchain lacks both.
if ! cargo fmt --version >/dev/null 2>&1 || ! cargo clippy --version >/dev/null 2>&1; then
  if command -v rustup >/dev/null 2>&1; then
    rustup -q component add rustfmt clippy
  else
    echo "error: cargo fmt and cargo clippy are needed (rustfmt and clippy; not installed with this Rust)" >&2
    exit 1
  fi
fi

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
