#!/usr/bin/env bash
# Sets Penumbra up on a Debian or Ubuntu machine: the Vulkan loader and Mesa's
# software Vulkan driver (lavapipe) and LLVM 19 (for Mitsuba) when absent, a lavapipe with ray
# queries where the system's Mesa is older than 24.1 (Debian 12: from bookworm-backports), then the
# package itself (built by maturin, editable) with its test dependencies and Dask (the `cluster`
# extra: tests/test_cluster.py). Needs cargo (rustup).
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
# Ray queries (method `raytraced`): Mesa's lavapipe has VK_KHR_ray_query from
# Mesa 24.1 on. Debian 12 ships 22.3; its bookworm-backports suite has 25.0,
# with the matching Mesa libraries (apt upgrades them together). Images of the
# other methods are the same under both (docs/methods/raytraced.md).
mesa="$(dpkg-query -W -f='${Version}' mesa-vulkan-drivers 2>/dev/null || true)"
if [ -n "$mesa" ] && dpkg --compare-versions "${mesa#*:}" lt 24.1; then
  codename="$(. /etc/os-release && echo "${VERSION_CODENAME:-}")"
  if [ "$codename" = "bookworm" ]; then
    echo "setup: Mesa $mesa has no ray queries; installing mesa-vulkan-drivers from bookworm-backports"
    if ! grep -rqs "bookworm-backports" /etc/apt/sources.list /etc/apt/sources.list.d/; then
      # The same archive as the system's bookworm suite.
      uri="$(awk '/^URIs:/ {print $2; exit}' /etc/apt/sources.list.d/debian.sources 2>/dev/null || true)"
      [ -n "$uri" ] || uri="$(awk '$1 == "deb" && $3 == "bookworm" {print $2; exit}' /etc/apt/sources.list 2>/dev/null || true)"
      [ -n "$uri" ] || { echo "setup: no bookworm archive in the apt sources to take backports from" >&2; exit 1; }
      printf 'Types: deb\nURIs: %s\nSuites: bookworm-backports\nComponents: main\nSigned-By: /usr/share/keyrings/debian-archive-keyring.gpg\n' "$uri" \
        | $SUDO tee /etc/apt/sources.list.d/bookworm-backports.sources >/dev/null
    fi
    $SUDO apt-get update -qq
    DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq -t bookworm-backports mesa-vulkan-drivers >/dev/null
    echo "setup: mesa-vulkan-drivers $(dpkg-query -W -f='${Version}' mesa-vulkan-drivers) installed"
  else
    echo "setup: Mesa $mesa has no ray queries and this is not Debian 12: method raytraced will raise GpuFeatureError" >&2
  fi
else
  echo "setup: mesa-vulkan-drivers ${mesa:-absent}: ray queries need nothing more"
fi
command -v cargo >/dev/null || { echo "setup: cargo not found; install Rust with rustup first" >&2; exit 1; }

python3 -m pip install -q --disable-pip-version-check "maturin==1.16.0"
python3 -m pip install -q --disable-pip-version-check -e ".[test,cluster]"
