#!/usr/bin/env bash
# The page's tests in a real browser, for .ci/run and for people: installs what is missing
# (Debian's chromium, the wasm32 target, wasm-bindgen-cli of the pinned version, the npm packages
# of package-lock.json), lints crates/wasm (not a workspace member), builds the page
# (web/build.sh) and the CLI, and runs web/tests/browser.mjs and web/tests/report.mjs (the
# pages of calibrate --report and cpa --report), whose last lines are 'N passed, N failed'.
# Exit 0 only when every test passed.
#
# Env: CARGO_TARGET_DIR (default: the repository's target/), SCREENSHOTS=dir (keep screenshots),
#      WEB_SKIP_LINT=1 (skip the wasm crate's fmt and clippy).
set -euo pipefail
WEB="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$WEB/.." && pwd)"
export CARGO_TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"
step() { echo "web/test.sh: $*" >&2; }

if [ ! -x /usr/bin/chromium ]; then
  step "installing Debian's chromium"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null
fi
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then
  step "installing node and npm"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq nodejs npm >/dev/null
fi
rustup target list --installed | grep -qx wasm32-unknown-unknown || rustup target add wasm32-unknown-unknown

WB_VERSION="$(sed -n 's/^wasm-bindgen = "=\([0-9.]*\)".*/\1/p' "$ROOT/crates/wasm/Cargo.toml")"
if ! command -v wasm-bindgen >/dev/null || [ "$(wasm-bindgen --version | awk '{print $2}')" != "$WB_VERSION" ]; then
  step "installing wasm-bindgen-cli $WB_VERSION (a few minutes, once)"
  # Not --locked: its lock file pins webpki-roots 1.0.11, which the registry reachable here
  # lacks; the version of wasm-bindgen-cli itself is exact.
  cargo install --quiet --version "$WB_VERSION" wasm-bindgen-cli --target-dir "$CARGO_TARGET_DIR/wasm-bindgen-cli"
fi

(cd "$WEB" && npm ci --no-audit --no-fund --loglevel=error)

if [ "${WEB_SKIP_LINT:-}" != 1 ]; then
  step "fmt and clippy of crates/wasm (wasm32-unknown-unknown)"
  cargo fmt --manifest-path "$ROOT/crates/wasm/Cargo.toml" -- --check
  RUSTFLAGS='--cfg getrandom_backend="wasm_js"' cargo clippy --quiet --locked \
    --manifest-path "$ROOT/crates/wasm/Cargo.toml" --target wasm32-unknown-unknown \
    --all-targets -- -D warnings
fi

step "building the page"
bash "$WEB/build.sh"
step "building the CLI (the tests compare the page with it)"
cargo build --quiet --locked --manifest-path "$ROOT/Cargo.toml" --bin urdf-dh

step "browser tests"
node "$WEB/tests/browser.mjs" "$CARGO_TARGET_DIR/debug/urdf-dh"

step "report pages in the browser (calibrate --report, cpa --report)"
node "$WEB/tests/report.mjs" "$CARGO_TARGET_DIR/debug/urdf-dh"
