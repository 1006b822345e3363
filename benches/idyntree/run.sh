#!/usr/bin/env bash
# Side by side with iDynTree (issue 12, section 4): the whole process of loading the Panda
# fixture and extracting its DH chain, iDynTree's C++ API (no verification) against
# `urdf-dh extract` (1000-sample verification included) and `urdf-dh --version` (the process
# floor). Needs g++, perf and Python 3 with pip; iDynTree comes from its PyPI wheel (static
# libraries and headers) into a virtual environment under $WORK (default: a temporary folder).
#
#   benches/idyntree/run.sh [RUNS]        # from the repository root; RUNS default 300
set -euo pipefail
runs=${1:-300}
root=$(cd "$(dirname "$0")/../.." && pwd)
work=${WORK:-$(mktemp -d)}
python3 -m venv "$work/venv"
"$work/venv/bin/pip" install -q idyntree
site=$("$work/venv/bin/python" -c 'import idyntree, os; print(os.path.dirname(os.path.dirname(idyntree.__file__)))')
libs=$site/idyntree.libs
g++ -O2 -std=c++17 -I"$site/idyntree/include" "$root/benches/idyntree/dh.cpp" -o "$work/dh" \
  -L"$site/idyntree/lib" -Wl,--start-group -lidyntree-modelio -lidyntree-modelio-xml \
  -lidyntree-model -lidyntree-core -Wl,--end-group "$libs"/libxml2-*.so* "$libs"/liblzma-*.so* \
  -Wl,--disable-new-dtags,-rpath,"$libs"
(cd "$root" && cargo build -q --release -p urdf-dh)
panda=$root/fixtures/robots/franka_panda/robot.urdf
bin=$root/target/release/urdf-dh
for cmd in "$work/dh $panda panda_link0 panda_link8" "$bin extract $panda" "$bin --version"; do
  # shellcheck disable=SC2086
  perf stat -r "$runs" $cmd 2>&1 >/dev/null | grep -E "task-clock|elapsed" | tr -s ' ' | tr '\n' ' '
  echo " <- ${cmd/$root\//}"
done
uptime
