#!/usr/bin/env bash
# Regenerates the ROS 2 test data in tests/data/bags/ with the reference
# implementations (@mcap/core, @foxglove/cdr, zstd/lz4; see
# scripts/fixtures/make_mcap_fixtures.mjs and write_sqlite_bag.py).
# Usage: scripts/make_ros2_fixtures.sh <KITTI raw drive folder with oxts/data>
#   e.g. scripts/make_ros2_fixtures.sh /work/shared/data/kitti_raw/2011_09_26_drive_0009_sync
# Needs Node.js >= 18 with npm (registry access for `npm ci`), the lz4
# command-line tool (Debian: lz4) and python3 (its sqlite3 module).
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/.." && pwd)"
drive="${1:?usage: $0 <KITTI raw drive folder with oxts/data>}"
command -v lz4 >/dev/null || "$here/install_deps.sh" lz4
out="$repo/tests/data/bags"
mkdir -p "$out"
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
(cd "$here/fixtures" && npm ci --no-audit --no-fund --silent)
node "$here/fixtures/make_mcap_fixtures.mjs" "$repo" "$drive/oxts/data" "$out" "$tmp/messages.jsonl"
rm -rf "$out/ros2_sqlite"
python3 "$here/fixtures/write_sqlite_bag.py" "$tmp/messages.jsonl" "$out/ros2_sqlite"
