#!/usr/bin/env bash
# Builds the urdf-dh page into web/dist/: the library compiled to WebAssembly (crates/wasm, with
# wasm-bindgen's glue), the page's scripts bundled with three.js by esbuild, the styles, and the
# project's own robots (fixtures/robots) as the gallery. Nothing in dist/ is fetched from the
# network at run time.
#
# Needs: the wasm32-unknown-unknown target (rustup target add wasm32-unknown-unknown),
# wasm-bindgen-cli of the version crates/wasm pins (cargo install --version X wasm-bindgen-cli),
# node and npm (the packages come from web/package-lock.json: npm ci). web/test.sh installs all
# of them.
#
# Usage: bash web/build.sh              (release build of the wasm: small and fast)
#        PROFILE=quick bash web/build.sh (while editing the library: no LTO, incremental)
set -euo pipefail
WEB="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$WEB/.." && pwd)"
PROFILE="${PROFILE:-release}"
TARGET_DIR="${CARGO_TARGET_DIR:-$ROOT/target}"
DIST="$WEB/dist"
BUILD="$WEB/build"

# The wasm-bindgen version the crate pins (`=X` in crates/wasm/Cargo.toml); the CLI must match
# it exactly, or the glue and the module disagree.
WB_VERSION="$(sed -n 's/^wasm-bindgen = "=\([0-9.]*\)".*/\1/p' "$ROOT/crates/wasm/Cargo.toml")"
if ! command -v wasm-bindgen >/dev/null || [ "$(wasm-bindgen --version | awk '{print $2}')" != "$WB_VERSION" ]; then
  echo "build.sh: wasm-bindgen $WB_VERSION is needed: cargo install --version $WB_VERSION wasm-bindgen-cli" >&2
  exit 2
fi

echo "build.sh: the library for wasm32-unknown-unknown ($PROFILE)" >&2
# getrandom's browser backend (crypto.getRandomValues): see crates/wasm/Cargo.toml.
RUSTFLAGS="${RUSTFLAGS:-} --cfg getrandom_backend=\"wasm_js\"" \
  cargo build --locked --manifest-path "$ROOT/crates/wasm/Cargo.toml" \
  --target wasm32-unknown-unknown --target-dir "$TARGET_DIR" --profile "$PROFILE"
OUT_PROFILE="$([ "$PROFILE" = dev ] && echo debug || echo "$PROFILE")"

rm -rf "$BUILD/pkg" && mkdir -p "$BUILD/pkg"
wasm-bindgen --target web --no-typescript --out-dir "$BUILD/pkg" \
  "$TARGET_DIR/wasm32-unknown-unknown/$OUT_PROFILE/urdf_dh_wasm.wasm"

if [ ! -x "$WEB/node_modules/.bin/esbuild" ] || [ "$WEB/package-lock.json" -nt "$WEB/node_modules/.package-lock.json" ]; then
  (cd "$WEB" && npm ci --no-audit --no-fund)
fi

rm -rf "$DIST" && mkdir -p "$DIST/robots"
"$WEB/node_modules/.bin/esbuild" "$WEB/src/main.js" --bundle --format=esm --minify \
  --target=es2022 --log-level=warning --outfile="$DIST/app.js"
cp "$BUILD/pkg/urdf_dh_wasm_bg.wasm" "$DIST/urdf_dh.wasm"
cp "$WEB/index.html" "$WEB/src/style.css" "$DIST/"

# The gallery: the project's own robots (authored for this project, see each SOURCE.md), an
# MJCF model and a xacro package (fixtures/mjcf, fixtures/xacro). Each entry: `dir` (its folder
# in dist), `files` (paths below it, the robot file first), `sheet` (a vendor sheet or null),
# `xacro_args`. The repository has no SDFormat robot of its own (its SDF tests carry their
# documents inline), so the gallery has none.
gallery="["
for dir in "$ROOT"/fixtures/robots/*/; do
  name="$(basename "$dir")"
  [ -f "$dir/robot.urdf" ] || continue
  mkdir -p "$DIST/robots/$name"
  cp "$dir/robot.urdf" "$DIST/robots/$name/"
  sheet=null
  if [ -f "$dir/vendor.yaml" ]; then
    cp "$dir/vendor.yaml" "$DIST/robots/$name/"
    sheet="\"robots/$name/vendor.yaml\""
  fi
  gallery+="{\"name\":\"$name\",\"dir\":\"robots/$name\",\"files\":[\"robot.urdf\"],\"sheet\":$sheet},"
done
mkdir -p "$DIST/robots/scara_mjcf" "$DIST/robots/demo_arm_xacro"
cp "$ROOT/fixtures/mjcf/scara.xml" "$DIST/robots/scara_mjcf/"
gallery+='{"name":"scara_mjcf","dir":"robots/scara_mjcf","files":["scara.xml"],"sheet":null},'
cp -r "$ROOT/fixtures/xacro/demo_arm_description" "$DIST/robots/demo_arm_xacro/"
gallery+='{"name":"demo_arm_xacro","dir":"robots/demo_arm_xacro","files":["demo_arm_description/urdf/arm.urdf.xacro","demo_arm_description/urdf/segment.xacro","demo_arm_description/config/links.yaml","demo_arm_description/package.xml"],"sheet":null,"xacro_args":"reach:=long"}'
gallery+="]"
echo "$gallery" > "$DIST/gallery.json"
# The user guide beside the page (web/dist is the project's site): docs/guide/*.md rendered
# to dist/guide/*.html by web/guide.mjs (marked, from package-lock.json).
node "$WEB/guide.mjs" "$ROOT/docs/guide" "$DIST/guide"
echo "build.sh: built $DIST ($(du -sh "$DIST" | cut -f1); wasm $(gzip -9c "$DIST/urdf_dh.wasm" | wc -c) bytes gzipped)" >&2
