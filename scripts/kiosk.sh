#!/usr/bin/env bash
# Builds and runs the kiosk on its embedded defaults (a recorded CMU walk drives the avatar).
# Extra arguments go to `fitroom kiosk`, e.g. --windowed.
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/deps.sh
fitroom_install_deps
exec cargo run --release --locked -- kiosk "$@"
