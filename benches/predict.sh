#!/usr/bin/env bash
# Time and memory of `urdf-dh predict` against the number of joint rows (issue 30, class 6):
# a simulated UR5 calibrated with its covariance, then 10^4, 10^5 and 10^6 rows of random joint
# values, each predicting the calibration's 3 targets with their uncertainties (and, at 10^5, the
# tool pose in the base frame). One line per run: rows, wall time, user time, max RSS
# (`/usr/bin/time`). Both should grow linearly with the rows.
#
#   benches/predict.sh            # release build, every size (about a minute on 2 cores)
#   BIN=path/to/urdf-dh benches/predict.sh 10000   # another binary, the sizes given
#
# The inputs are generated in a temporary directory (python3, stdlib only) and removed at the
# end; nothing here is a test: the figures are for the notes and docs/scale.md.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ -z "${BIN:-}" ]; then
  cargo build --release --locked --quiet
  BIN="$PWD/target/release/urdf-dh"
fi
UR5="$PWD/fixtures/robots/ur5/vendor.yaml"
SIZES=("${@:-10000 100000 1000000}")
WORK="$(mktemp -d)"
trap 'rm -rf "$WORK"' EXIT
cd "$WORK"

"$BIN" simulate --model "$UR5" --poses 200 --out ur5.csv --noise 5e-5 --targets 3 \
  --error shoulder_lift_joint.a=0.0005 --error elbow_joint.theta=0.001 --seed 7 >/dev/null 2>&1
"$BIN" calibrate --model "$UR5" --data ur5.csv --out cal.yaml >/dev/null 2>&1

for n in ${SIZES[@]}; do
  python3 - "$n" <<'PY'
import random, sys
n = int(sys.argv[1])
random.seed(5)
names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
         "wrist_2_joint", "wrist_3_joint"]
with open(f"q{n}.csv", "w") as f:
    f.write(",".join(names) + ",config\n")
    for i in range(n):
        f.write(",".join(repr(random.uniform(-3, 3)) for _ in names) + f",p{i}\n")
PY
  /usr/bin/time -f "predict $n rows x 3 targets: wall %e s, user %U s, max RSS %M KB" \
    "$BIN" predict --model cal.yaml --joints "q$n.csv" --out "p$n.csv" >/dev/null
  if [ "$n" = 100000 ]; then
    /usr/bin/time -f "predict $n rows, tool pose in the base frame: wall %e s, user %U s, max RSS %M KB" \
      "$BIN" predict --model cal.yaml --joints "q$n.csv" --targets tool --frame base --out "t$n.csv" >/dev/null
  fi
  rm -f "q$n.csv" "p$n.csv" "t$n.csv"
done
