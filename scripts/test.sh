#!/usr/bin/env bash
# The test command: the core crate's tests (naga validation of every shader,
# GPU tests on whatever adapter exists, lavapipe in CI), the check of the
# hand-written type stubs against the compiled module, and pytest.
# Extra arguments go to pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
# Mesa's Vulkan loader complains on stderr without a runtime dir; give it one.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
  export XDG_RUNTIME_DIR="$(mktemp -d)"
fi

cargo test -p penumbra-core
python3 -m mypy.stubtest penumbra._core
python3 -m mypy python/penumbra
python3 -m pytest "$@"
