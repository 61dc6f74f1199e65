#!/usr/bin/env bash
# Pinocchio reference timings on the Panda (see README.md beside this file). Not run by CI.
#
#   bash crates/dvrk-model/benches/pinocchio/run.sh [URDF] [samples] [rounds]
#
# Environment:
#   PYTHON   a python whose environment has the `pin` wheel (default: .venv-ci/bin/python
#            of the repository if it imports pinocchio, else a venv made in
#            target/pinbench/venv with `pip install pin`)
#   MARCH    g++ -march (default x86-64: the baseline, SSE2, that our Rust build targets and
#            that the wheel's libraries were built for; others crash, see below)
#   CXX      C++ compiler (default g++)
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../../../.." && pwd)"
urdf="${1:-$root/../shared/anchors/panda_arm_7dof.urdf}"
samples="${2:-64}"
rounds="${3:-15}"
march="${MARCH:-x86-64}"
cxx="${CXX:-g++}"
work="$root/target/pinbench"
mkdir -p "$work"

# A python with the `pin` wheel (Pinocchio 4.1).
if [[ -z "${PYTHON:-}" ]]; then
  if [[ -x "$root/.venv-ci/bin/python" ]] && "$root/.venv-ci/bin/python" -c "import pinocchio" 2>/dev/null; then
    PYTHON="$root/.venv-ci/bin/python"
  else
    if [[ ! -x "$work/venv/bin/python" ]]; then
      python3 -m venv "$work/venv"
    fi
    "$work/venv/bin/python" -c "import pinocchio" 2>/dev/null ||
      "$work/venv/bin/python" -m pip install --quiet 'pin==4.1.*'
    PYTHON="$work/venv/bin/python"
  fi
fi
version="$("$PYTHON" -c "import pinocchio; print(pinocchio.__version__)")"

# The wheels' prefix (cmeel.prefix under site-packages): include/ and lib/ of Pinocchio,
# boost, urdfdom, console_bridge, tinyxml2.
prefix="$("$PYTHON" -c "import cmeel, pathlib; print(pathlib.Path(cmeel.__file__).resolve().parent.parent / 'cmeel.prefix')")"
[[ -f "$prefix/include/pinocchio/config.hpp" ]] || { echo "no Pinocchio headers under $prefix" >&2; exit 1; }

# Eigen and urdfdom_headers: the runtime wheels do not ship their headers (cmeel-eigen and
# cmeel-urdfdom-headers are only in the `build` extras of `pin` and `cmeel-urdfdom`), so
# take them from the prefix if there, else install those two header-only wheels, at the
# versions Pinocchio 4.1 was built with, into target/pinbench/headers (the python's own
# environment is left as is).
eigen="$work/headers/eigen/cmeel.prefix/include/eigen3"
urdfh="$work/headers/urdfdom-headers/cmeel.prefix/include/urdfdom_headers"
if [[ -f "$prefix/include/eigen3/Eigen/Core" ]]; then
  eigen="$prefix/include/eigen3"
elif [[ ! -f "$eigen/Eigen/Core" ]]; then
  "$PYTHON" -m pip install --quiet --no-deps --target "$work/headers/eigen" 'cmeel-eigen==3.4.1'
fi
if [[ -f "$prefix/include/urdfdom_headers/urdf_model/model.h" ]]; then
  urdfh="$prefix/include/urdfdom_headers"
elif [[ ! -f "$urdfh/urdf_model/model.h" ]]; then
  "$PYTHON" -m pip install --quiet --no-deps --target "$work/headers/urdfdom-headers" \
    'cmeel-urdfdom-headers==3.0.0'
fi

# Compile definitions of the wheel's CMake targets (pinocchio::pinocchio_headers and
# pinocchio_parsers), without PINOCCHIO_ENABLE_TEMPLATE_INSTANTIATION: the algorithms'
# templates are compiled here with our flags, not taken from libpinocchio_default.so.
defs=(
  -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30
  -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12
  -DPINOCCHIO_WITH_URDFDOM -DPINOCCHIO_URDFDOM_HEADERS_MAJOR_VERSION=3
  -DPINOCCHIO_URDFDOM_HEADERS_MINOR_VERSION=0 -DPINOCCHIO_URDFDOM_HEADERS_PATCH_VERSION=0
)
# The wheel's libraries were built for baseline x86-64. Another -march (tried: native, with
# AVX-512, with and without -DEIGEN_MAX_ALIGN_BYTES=16) gives a binary whose Model does not
# match the one libpinocchio_parsers' buildModel fills: it crashes (in ~Model). Baseline only.
if [[ "$march" != x86-64 ]]; then
  echo "warning: -march=$march does not match the wheel's libraries; expect a crash" >&2
fi
bin="$work/panda-$march"
if [[ ! -x "$bin" || "$here/panda.cpp" -nt "$bin" || "$here/states.hpp" -nt "$bin" || "$0" -nt "$bin" ]]; then
  echo "compiling $bin (Pinocchio $version, -O3 -DNDEBUG -march=$march; a minute or two)" >&2
  "$cxx" -O3 -DNDEBUG -march="$march" -std=c++17 -w "${defs[@]}" \
    -isystem "$prefix/include" -isystem "$prefix/include/pinocchio/deprecated" \
    -isystem "$eigen" -isystem "$urdfh" -isystem "$prefix/include/urdfdom" \
    "$here/panda.cpp" -o "$bin" \
    -L"$prefix/lib" -Wl,-rpath,"$prefix/lib" \
    -lpinocchio_parsers -lpinocchio_default -lurdfdom_model -lconsole_bridge -ltinyxml2
fi

echo "$("$cxx" --version | head -1), -O3 -DNDEBUG -march=$march; $(uptime | sed 's/.*load/load/')"
"$bin" "$urdf" "$samples" "$rounds"
