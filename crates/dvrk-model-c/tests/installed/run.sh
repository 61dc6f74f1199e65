#!/bin/sh
# The dvrk-model C library as a controller's build uses it, from an install prefix
# (.ci/run runs this after the Rust tests):
#   DVRK_IDENT_BIN=target/release/dvrk-ident [CMAKE=cmake] run.sh WORKDIR
# 1. crates/dvrk-model-c/install.sh WORKDIR/prefix (with DVRK_MODEL_LIBDIR, the libraries
#    already built there; else it builds them);
# 2. fits the bundled example with the command line (--preset dvrk: delays and Stribeck
#    terms) into WORKDIR/psm.json;
# 3. compiles torque.c with `cc -O2` and `pkg-config --cflags --libs dvrk_model` and
#    checks its inverse dynamics against `dvrk-ident model psm --torque --params
#    WORKDIR/psm.json` to 1e-12 at four states, one of them at rest (dq = ddq = 0: the
#    static torque a gravity compensation applies; the PSM has no known forces, which
#    dvrk_inverse_dynamics adds and `model --torque` leaves out);
# 4. with CMake: configures this folder against the prefix (find_package(dvrk_model)),
#    builds the README's C++ example (shared library) and torque.c (static library),
#    runs both, and requires the static build to print what the pkg-config build printed.
# Any difference or failure exits non-zero.
set -eu
if [ $# -ne 1 ]; then
  echo "usage: DVRK_IDENT_BIN=... $0 WORKDIR" >&2
  exit 2
fi
here=$(cd "$(dirname "$0")" && pwd)
work=$1
bin=${DVRK_IDENT_BIN:?set DVRK_IDENT_BIN to the dvrk-ident binary}
python=${PYTHON:-python3}
rm -rf "$work"
mkdir -p "$work"
work=$(cd "$work" && pwd)
prefix=$work/prefix

"$here/../../install.sh" "$prefix"
"$bin" fit "$here/../../../../examples/psm_excitation.mcap" --robot psm --preset dvrk \
  --quiet --out "$work/psm.json" >/dev/null

export PKG_CONFIG_PATH="$prefix/lib/pkgconfig"
# shellcheck disable=SC2046 # the flags are words
cc -O2 -Wall -Wextra -Werror -o "$work/torque" "$here/torque.c" \
  $(pkg-config --cflags --libs dvrk_model) -Wl,-rpath,"$prefix/lib"

# (q, dq, ddq) in model order: yaw, pitch (rad), insertion (m), the four instrument
# joints (rad); the last state at rest, where the inverse dynamics is the static torque.
states='0.1,-0.2,0.12,0.3,-0.4,0.2,0.1 0.5,-0.3,0.8,1.2,-0.7,0.4,-0.2 -1.0,0.4,-2.0,0.5,1.5,-0.6,0.9
-0.3,0.2,0.15,-0.5,0.1,0.3,-0.2 -0.2,0.1,0.05,0.3,-0.6,0.2,0.4 0.3,-0.8,1.1,-0.4,0.2,0.9,-0.5
0.6,0.4,0.09,0.2,0.2,-0.3,0.1 0,0,0,0,0,0,0 0,0,0,0,0,0,0'
echo "$states" | while read -r q dq ddq; do
  "$work/torque" "$work/psm.json" "$q" "$dq" "$ddq" >"$work/c.json"
  "$bin" model psm --torque --q "$q" --dq "$dq" --ddq "$ddq" --params "$work/psm.json" \
    >"$work/cli.json"
  "$python" - "$work/c.json" "$work/cli.json" "$q" "$dq" "$ddq" <<'PY'
import json, sys
c = json.load(open(sys.argv[1]))["tau"]
cli = json.load(open(sys.argv[2]))["tau"]
assert len(c) == len(cli) == 7, (c, cli)
worst = max(abs(x - y) / max(1.0, abs(y)) for x, y in zip(c, cli))
print(f"q = {sys.argv[3]}, dq = {sys.argv[4]}, ddq = {sys.argv[5]}: C vs model --torque {worst:.1e}")
if worst > 1e-12:
    sys.exit(f"the installed C library differs from dvrk-ident model --torque: {c} vs {cli}")
PY
done

cmake=${CMAKE:-cmake}
if ! "$cmake" --version >/dev/null 2>&1; then
  echo "SKIPPED: the CMake package check (no cmake; CMAKE=path/to/cmake)"
  exit 0
fi
"$cmake" -S "$here" -B "$work/cmake" -DCMAKE_PREFIX_PATH="$prefix" \
  -DCMAKE_BUILD_TYPE=Release >"$work/cmake.log" 2>&1 || { cat "$work/cmake.log"; exit 1; }
"$cmake" --build "$work/cmake" >>"$work/cmake.log" 2>&1 || { cat "$work/cmake.log"; exit 1; }
q='0.1,-0.2,0.12,0.3,-0.4,0.2,0.1'
dq='0.5,-0.3,0.8,1.2,-0.7,0.4,-0.2'
ddq='-1.0,0.4,-2.0,0.5,1.5,-0.6,0.9'
"$work/torque" "$work/psm.json" "$q" "$dq" "$ddq" >"$work/shared.json"
"$work/cmake/torque_static" "$work/psm.json" "$q" "$dq" "$ddq" >"$work/static.json"
cmp "$work/shared.json" "$work/static.json"
"$work/cmake/readme" "$work/psm.json"
echo "find_package(dvrk_model): the README's C++ example and the static build run"
