#!/usr/bin/env bash
# Fills corpus/<target>/ with the project's real files as seeds: the fixture robots, the
# invalid corpus, their sheets (vendor sheets and extract's own output) and measurement CSVs.
# The CSV target reads one leading mode byte (see fuzz_targets/csv.rs): each CSV is seeded with
# the modes 0 (m, rad), 1 (mm), 2 (deg) and 4 (first joint prismatic).
set -euo pipefail
cd "$(dirname "$0")"
root=..
mkdir -p corpus/urdf corpus/sheet corpus/csv corpus/tree
for f in "$root"/fixtures/robots/*/robot.urdf "$root"/fixtures/invalid/urdf/*.urdf; do
  cp "$f" "corpus/urdf/$(basename "$(dirname "$f")")-$(basename "$f")"
done
for f in "$root"/fixtures/robots/*/vendor.yaml "$root"/fixtures/invalid/sheet/*; do
  cp "$f" "corpus/sheet/$(basename "$(dirname "$f")")-$(basename "$f")"
done
# Tree sheets: the DLR torso-and-arms model, the tree cases of the invalid corpus, and the serial
# sheets (which the tree reader must refuse cleanly).
for f in "$root"/fixtures/measured/*/model.yaml "$root"/fixtures/invalid/sheet/*.yaml; do
  cp "$f" "corpus/tree/$(basename "$(dirname "$f")")-$(basename "$f")"
done
bin="$root/target/debug/urdf-dh"
if [ -x "$bin" ]; then
  for f in "$root"/fixtures/robots/*/robot.urdf; do
    id=$(basename "$(dirname "$f")")
    "$bin" extract "$f" --format yaml > "corpus/sheet/$id-extract.yaml" 2>/dev/null || true
    "$bin" extract "$f" --format json --convention modified --length-unit mm --angle-unit deg \
      > "corpus/sheet/$id-extract.json" 2>/dev/null || true
  done
fi
for f in seeds/csv/*.csv "$root"/fixtures/invalid/csv/*.csv; do
  [ -e "$f" ] || continue
  for mode in 0 1 2 4; do
    { printf '%s' "$mode"; cat "$f"; } > "corpus/csv/$mode-$(basename "$f")"
  done
done
echo "seeded: $(ls corpus/urdf | wc -l) urdf, $(ls corpus/sheet | wc -l) sheet, $(ls corpus/csv | wc -l) csv, $(ls corpus/tree | wc -l) tree"
