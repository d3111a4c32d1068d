#!/usr/bin/env bash
# Runs every test of the workspace (unit, data, headless ECS and lavapipe screenshot tests).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
fitroom_install_deps
cargo test --workspace --all-targets --locked "$@"
