#!/usr/bin/env bash
# README's test command: every test of the workspace (`cargo test --workspace --locked`, with
# any arguments given here passed on), then the list of the checks that were skipped and why.
#
# A test that cannot make a check here (../shared absent, an optional tool not installed) calls
# test_skips::skip (crates/test-skips), which appends a line to $URDF_DH_SKIP_LOG; this script
# empties that file first and prints it, sorted and counted, at the end. The exit code is
# cargo's.
set -uo pipefail
cd "$(dirname "$0")/.."

target="${CARGO_TARGET_DIR:-target}"
mkdir -p "$target"
log="$(cd "$target" && pwd)/skipped-tests.txt"
: >"$log"
export URDF_DH_SKIP_LOG="$log"

cargo test --workspace --locked "$@"
status=$?

echo
if [ -s "$log" ]; then
  echo "skipped ($(wc -l <"$log" | tr -d ' ')):"
  sort "$log" | sed 's/^SKIPPED: /  /'
else
  echo "skipped: none"
fi
exit "$status"
