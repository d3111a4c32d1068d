#!/usr/bin/env bash
# Runs every test of the workspace (unit, data, headless ECS and lavapipe screenshot tests).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
fitroom_install_deps
# The Vulkan loader and winit want a runtime dir; CI shells have none.
if [ -z "${XDG_RUNTIME_DIR:-}" ]; then
    XDG_RUNTIME_DIR="$(mktemp -d)"
    export XDG_RUNTIME_DIR
fi
cargo test --workspace --all-targets --locked "$@"
# The cloth core's own tests again, with the debug assertions and overflow checks that the dev
# profile leaves out of its hot loops (see Cargo.toml).
cargo test -p fitroom_cloth --lib --tests --profile checked --locked "$@"
