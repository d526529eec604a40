#!/usr/bin/env bash
# Packages every crate oit publishes and builds each package as crates.io would (issue 42, item 6):
# `cargo package` over the published crates together, so each one that depends on a sibling is
# verified against the sibling's package (cargo resolves them from a local overlay of the packages
# just made), not against the workspace's folders. Heavy (every package is built from scratch in
# the dev profile: minutes, not seconds); the test suite's cheap check is
# tests/tests/packaging.rs (`cargo package --list`, manifests, shipped data).
#   bench/local/package.sh            # package and verify all
#   bench/local/package.sh --no-verify  # package only (seconds)
# The .crate files land in target/package/ (or $CARGO_TARGET_DIR/package/).
set -euo pipefail
cd "$(dirname "$0")/../.."
# oit-tests and oit-fuzz are `publish = false`: workspace-only test harnesses
exec cargo package --workspace --exclude oit-tests --exclude oit-fuzz --allow-dirty "$@"
