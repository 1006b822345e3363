#!/usr/bin/env bash
# Time and memory of the release binary on the large and hostile inputs of issue 11 (§9):
# wall time and maximum resident set size from `/usr/bin/time`, one line per case.
#
#   benches/scale.sh              # every case (about 2 minutes on 2 cores, 1 GB of temporary files)
#   benches/scale.sh calibrate    # the cases whose name contains "calibrate"
#   benches/scale.sh Agile        # the Agile Justin diagnosis of issue 13 §7 (needs ../shared)
#
# The inputs are generated in a temporary directory (python3, stdlib only) and removed at the
# end; nothing here is a test: the figures are for the notes and docs/scale.md.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release --locked --quiet
BIN="$PWD/target/release/urdf-dh"
FILTER="${1:-}"
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"

python3 - <<'PY'
# 50 MB of empty <gazebo/> elements around a 2-joint arm.
arm = ('<link name="base"/><link name="l1"/><link name="l2"/>'
       '<joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
       '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
       '<joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>'
       '<origin xyz="0.3 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>')
with open("gazebo50mb.urdf", "w") as f:
    f.write('<?xml version="1.0"?>\n<robot name="g">' + arm + "\n")
    f.write("<gazebo/>\n" * (50_000_000 // 10))
    f.write("</robot>\n")
# A 100 000-joint chain of axes along z, x, y in turn (well conditioned).
axes = ["0 0 1", "1 0 0", "0 1 0"]
with open("chain100k.urdf", "w") as f:
    f.write('<?xml version="1.0"?>\n<robot name="long"><link name="l0"/>\n')
    for i in range(100_000):
        f.write(f'<link name="l{i+1}"/><joint name="j{i}" type="revolute"><parent link="l{i}"/>'
                f'<child link="l{i+1}"/><origin xyz="0.001 0 0.002"/><axis xyz="{axes[i % 3]}"/>'
                '<limit lower="-1" upper="1" effort="1" velocity="1"/></joint>\n')
    f.write("</robot>\n")
# 200 000 leaves on one base: refused (no single tip).
with open("leaves200k.urdf", "w") as f:
    f.write('<?xml version="1.0"?>\n<robot name="leaves"><link name="base"/>\n')
    for i in range(200_000):
        f.write(f'<link name="t{i}"/><joint name="j{i}" type="revolute"><parent link="base"/>'
                f'<child link="t{i}"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>\n')
    f.write("</robot>\n")
# 100 000 nested '[' as an inertials file and as a Hilti import.
with open("nested.yaml", "w") as f:
    f.write("links: " + "[" * 100_000 + "\n")
PY
cp nested.yaml nested_hilti.yaml

# 200 samples, each its own target; 2 000 000 rows of a simulated Panda (two 1 000 000-pose
# runs of the same truth; the second copy's configs renamed).
PANDA="$OLDPWD/fixtures/robots/franka_panda/robot.urdf"
"$BIN" simulate --model "$PANDA" --poses 200 --seed 3 --out own_targets.csv >/dev/null 2>&1
"$BIN" simulate --model "$PANDA" --poses 1000000 --noise 5e-5 --random-errors 0.001,0.002 --seed 1 \
  --out half.csv --truth truth.yaml >/dev/null 2>&1
{ cat half.csv; grep -v '^#' half.csv | tail -n +2 | awk -F, 'BEGIN{OFS=","}{$12="r"$12; print}'; } > rows2m.csv
rm half.csv
python3 - <<'PY'
# Give each of the 200 samples its own target name.
rows = open("own_targets.csv").read().splitlines()
head = [r for r in rows if r.startswith("#")]
body = [r for r in rows if not r.startswith("#")]
cols = body[0].split(",")
t = cols.index("target")
out = head + [body[0]]
for i, r in enumerate(body[1:]):
    f = r.split(",")
    f[t] = f"t{i}"
    out.append(",".join(f))
open("own_targets.csv", "w").write("\n".join(out) + "\n")
PY

run() {
  local name="$1"; shift
  if [ -n "$FILTER" ] && [[ "$name" != *"$FILTER"* ]]; then return; fi
  local rc=0
  /usr/bin/time -f "%e %M" -o time.txt "$@" >out.txt 2>err.txt || rc=$?
  read -r wall rss < <(tail -n 1 time.txt)
  printf '%-52s exit %3s  %7.2f s  %8.1f MB  %s\n' "$name" "$rc" "$wall" "$(echo "$rss / 1024" | bc -l)" \
    "$(grep -m1 'error:' err.txt | cut -c1-90 || true)"
}

echo "urdf-dh $("$BIN" --version | cut -d' ' -f2), $(nproc) cores; wall time, max RSS, exit code, first error line"
run "extract 50 MB of <gazebo/>"                 "$BIN" extract gazebo50mb.urdf
run "extract 100 000-joint chain (text)"         "$BIN" extract chain100k.urdf
run "extract 100 000-joint chain (yaml)"         "$BIN" extract chain100k.urdf --format yaml
run "extract 100 000-joint chain (json)"         "$BIN" extract chain100k.urdf --format json
run "extract 200 000 leaves (refused)"           "$BIN" extract leaves200k.urdf
ARM="$OLDPWD/fixtures/invalid/urdf/valid_arm.urdf"
ARM_DATA="$OLDPWD/fixtures/invalid/csv/valid_arm.csv"
run "calibrate --inertials of 100 000 '['"       "$BIN" calibrate --model "$ARM" --data "$ARM_DATA" --inertials nested.yaml
run "import --layout hilti of 100 000 '['"       "$BIN" import --layout hilti nested_hilti.yaml --out x.csv
run "calibrate 200 samples, each its own target" "$BIN" calibrate --model "$PANDA" --data own_targets.csv
run "calibrate 2 000 000 CSV rows"               "$BIN" calibrate --model "$PANDA" --data rows2m.csv
run "extract - < /dev/zero (1 GB offered)"       bash -c "head -c 1000000000 /dev/zero | '$BIN' extract -"
run "simulate --poses 100000000"                 "$BIN" simulate --model "$PANDA" --poses 100000000 --out s.csv
run "extract --samples 1000000000"               "$BIN" extract "$PANDA" --samples 1000000000

# Issue 13 §7: the README's Agile Justin diagnosis (134 s when the issue was filed), when
# ../shared/measured is beside the project.
DLR="$OLDPWD/../shared/measured/dlr_agile_justin_vicon/measurements.csv"
if [ -f "$DLR" ]; then
  "$BIN" import --layout dlr "$DLR" --out dlr.csv >/dev/null 2>&1
  run "calibrate Agile Justin --effects auto"    "$BIN" calibrate --model "$OLDPWD/fixtures/measured/dlr_agile_justin/model.yaml" \
    --data dlr.csv --folds 10 --effects auto --max-effects 40 --quiet
else
  echo "calibrate Agile Justin --effects auto: skipped ($DLR is absent)"
fi
