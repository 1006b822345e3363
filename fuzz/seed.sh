#!/usr/bin/env bash
# Fills corpus/<target>/ with the project's real files as seeds: the fixture robots, the
# invalid corpus, their sheets (vendor sheets and extract's own output) and measurement CSVs.
# The CSV target reads one leading mode byte (see fuzz_targets/csv.rs): each CSV is seeded with
# the modes 0 (m, rad), 1 (mm), 2 (deg) and 4 (first joint prismatic).
set -euo pipefail
cd "$(dirname "$0")"
root=..
mkdir -p corpus/urdf corpus/sheet corpus/csv corpus/tree corpus/import
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
# Import layouts: the head (40 lines) of each published set in ../shared/measured, where it is
# present (local seeds only: corpus/ is not committed). One leading byte picks the layout, in
# the order of Layout::ALL; a layout's files are joined with NUL in the order of Layout::files.
m="$root/../shared/measured"
seed_import() { # byte name files...
  local byte=$1 name=$2; shift 2
  { printf "\\$(printf '%03o' "$byte")"
    local first=1
    for f in "$@"; do
      [ $first = 1 ] || printf '\0'
      first=0
      head -n 40 "$f"
    done; } > "corpus/import/$name"
}
if [ -d "$m" ]; then
  seed_import 0 innopolis "$m"/innopolis_fanuc_r2000ic_165f_3markers/calibration_dataset.csv
  seed_import 1 boby "$m"/boby_klimchik_laser_tracker_cpa/N1N2N3Jval.csv
  seed_import 2 dlr "$m"/dlr_agile_justin_vicon/measurements.csv
  l="$m"/liaowu_abb_irb120_position
  seed_import 3 liaowu "$l"/CaliJointAngles.csv "$l"/CaliPosition.csv "$l"/TestJointAngles.csv \
    "$l"/TestPosition.csv "$l"/TestJointAngles2.csv "$l"/TestPosition2.csv
  seed_import 4 hilti "$m"/hilti_trailblazer_total_station/flat.yaml
  k="$m"/mukca_ball_socket_panda_iiwa/data/panda_6/front
  [ -f "$k/hole_0.csv" ] && seed_import 5 mukca "$k"/hole_0.csv "$k"/hole_1.csv
fi
echo "seeded: $(ls corpus/urdf | wc -l) urdf, $(ls corpus/sheet | wc -l) sheet, $(ls corpus/csv | wc -l) csv, $(ls corpus/tree | wc -l) tree, $(ls corpus/import | wc -l) import"
