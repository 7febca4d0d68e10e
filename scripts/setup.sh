#!/usr/bin/env bash
# Sets Penumbra up on a Debian or Ubuntu machine: the Vulkan loader and Mesa's
# software Vulkan driver (lavapipe) and LLVM 19 (for Mitsuba) when absent, then the package itself
# (built by maturin, editable) with its test dependencies. Needs cargo (rustup).
set -euo pipefail
cd "$(dirname "$0")/.."

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
# libllvm19: Mitsuba's fast llvm variant needs an LLVM of 17 or newer (the
# LLVM 15 that Mesa pulls in crashes it); Penumbra points Dr.Jit at it.
if ! ldconfig -p | grep -q 'libvulkan.so.1' || ! ls /usr/share/vulkan/icd.d/lvp_icd*.json >/dev/null 2>&1 \
   || ! ls /usr/lib/*/libLLVM-19.so* >/dev/null 2>&1; then
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq mesa-vulkan-drivers libvulkan1 libllvm19 >/dev/null
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust with rustup first" >&2; exit 1; }

python3 -m pip install -q --disable-pip-version-check "maturin==1.16.0"
python3 -m pip install -q --disable-pip-version-check -e ".[test]"
