#!/usr/bin/env bash
# GPU timings of every method at 1920x1080 in one short run on the GPU machine
# (docs/gpu_timings.md). Run from the repository root.
#
#   bash scripts/device_timings.sh prepare   # here: build, copy into .device/, fetch .gl/*.deb
#   bash scripts/device_timings.sh           # there: unpack the Vulkan loader, run, results in $OUT
#
# `prepare` needs cargo and apt-get; the run needs neither (the GPU machine has
# no Rust and no package registry): it uses the release binary and meshes in
# .device/ and the Vulkan loader packages in .gl/, both ignored by git and
# carried by the `run` call. Extra arguments of the run go to the binary
# (`--size 320x180 --repeats 1`, say).
set -uo pipefail
cd "$(dirname "$0")/.."

MESHES_SRC=${MESHES_SRC:-../shared/meshes}
MESH_FILES="cube.obj spot.obj teapot-mcguire-closed.obj bun_zipper.ply"

if [ "${1:-}" = prepare ]; then
  set -e
  cargo build --release --example gpu_timings -p penumbra-core
  mkdir -p .device/meshes
  cp target/release/examples/gpu_timings .device/gpu_timings
  strip --strip-debug .device/gpu_timings 2>/dev/null || true
  for f in $MESH_FILES; do
    if [ -f "$MESHES_SRC/$f" ]; then install -m 0644 "$MESHES_SRC/$f" .device/meshes/; else echo "note: $MESHES_SRC/$f absent, its scene will report an error"; fi
  done
  if ! ls .gl/libvulkan1_*.deb >/dev/null 2>&1; then
    # /work/.library/device/README.md: the amd64 loader packages, whatever this machine's processor.
    mkdir -p .gl /tmp/amd64/partial
    o='-oAPT::Architecture=amd64 -oAPT::Architectures=amd64 -oDir::State::Lists=/tmp/amd64'
    apt-get $o update
    (cd .gl && apt-get $o download libvulkan1 libegl1 libglvnd0 libopengl0 libgl1 libglx0 libgles2)
  fi
  du -sh .device .gl
  du -cb .device .gl | tail -1 | awk '{printf "carried: %.1f MiB (the limit is 64 MiB with the tracked files)\n", $1 / 1048576}'
  exit 0
fi

OUT=${OUT:-out/device_timings}
mkdir -p "$OUT"
export XDG_RUNTIME_DIR=${XDG_RUNTIME_DIR:-$(mktemp -d)}
BIN=${BIN:-.device/gpu_timings}
if [ ! -x "$BIN" ]; then
  echo "no $BIN: run 'bash scripts/device_timings.sh prepare' where cargo is, and carry .device" | tee "$OUT/timings.txt"
  exit 1
fi

# The Vulkan loader, where the machine has none (/work/.library/device/README.md).
if ! ldconfig -p | grep -q libvulkan.so.1; then
  for f in .gl/*.deb; do dpkg -x "$f" /; done
  ldconfig
fi
nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.sm,clocks.max.sm --format=csv >"$OUT/nvidia-smi.csv" 2>&1 || true

# The adapter: exit 0 hardware, 3 software, 1 none. Where the loader finds no
# hardware adapter, point it at the NVIDIA driver's ICD and ask again; keep
# that only if it helps (the run then goes on with whatever adapter there is,
# and says which).
NVIDIA_ICD=/usr/local/nvidia/share/vulkan/icd.d/nvidia_icd.json
NVIDIA_EGL=/usr/local/nvidia/share/glvnd/egl_vendor.d/10_nvidia.json
timeout 60 "$BIN" --adapter-only
if [ $? != 0 ] && [ -f "$NVIDIA_ICD" ]; then
  echo "no hardware adapter found; trying VK_DRIVER_FILES=$NVIDIA_ICD"
  if VK_DRIVER_FILES=$NVIDIA_ICD __EGL_VENDOR_LIBRARY_FILENAMES=$NVIDIA_EGL timeout 60 "$BIN" --adapter-only; then
    export VK_DRIVER_FILES=$NVIDIA_ICD __EGL_VENDOR_LIBRARY_FILENAMES=$NVIDIA_EGL
  fi
fi

# Every scene and method at 1920x1080: no new one starts after 240 s, and the
# whole run is stopped at 300 s; the JSON and CSV are rewritten after every
# scene and method, so a stopped run leaves what it measured.
timeout -k 10 300 "$BIN" --size 1920x1080 --repeats 5 --max-seconds 10 --budget-seconds 240 \
  --meshes .device/meshes --out "$OUT/timings.json" --out "$OUT/timings.csv" "$@" 2>&1 | tee "$OUT/timings.txt"
status=${PIPESTATUS[0]}
echo "gpu_timings exit status $status" | tee -a "$OUT/timings.txt"
exit "$status"
