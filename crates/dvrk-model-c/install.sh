#!/bin/sh
# Installs the dvrk-model C library into PREFIX, laid out for a C or C++ build to find:
#   PREFIX/lib/libdvrk_model_c.{so,a}              the shared and the static library
#   PREFIX/include/dvrk_model.h, dvrk_model.hpp    the C header and the C++ wrapper
#   PREFIX/lib/pkgconfig/dvrk_model.pc             pkg-config --cflags --libs dvrk_model
#   PREFIX/lib/cmake/dvrk_model/*.cmake            find_package(dvrk_model) in CMake
#
#   crates/dvrk-model-c/install.sh PREFIX
#
# builds the libraries first (cargo build --release -p dvrk-model-c). With
# DVRK_MODEL_LIBDIR=DIR it takes them from DIR instead and builds nothing (the crate's
# tests install the libraries their own run built). Nothing is written until both
# libraries and both headers are found.
set -eu
if [ $# -ne 1 ] || [ -z "$1" ]; then
  echo "usage: $0 PREFIX" >&2
  exit 2
fi
prefix=$1
here=$(cd "$(dirname "$0")" && pwd)
version=$(sed -n 's/^version = "\(.*\)"$/\1/p' "$here/../../Cargo.toml" | head -n 1)
if [ -z "$version" ]; then
  echo "$0: no version in $here/../../Cargo.toml" >&2
  exit 1
fi
if [ -n "${DVRK_MODEL_LIBDIR:-}" ]; then
  libdir=$DVRK_MODEL_LIBDIR
else
  (cd "$here/../.." && cargo build --release -p dvrk-model-c)
  libdir=$(cd "$here/../.." && cargo metadata --format-version 1 --no-deps |
    sed -n 's/.*"target_directory":"\([^"]*\)".*/\1/p')/release
fi
case $(uname -s) in
  Darwin) shared=libdvrk_model_c.dylib ;;
  *) shared=libdvrk_model_c.so ;;
esac
for file in "$libdir/$shared" "$libdir/libdvrk_model_c.a" \
  "$here/include/dvrk_model.h" "$here/include/dvrk_model.hpp"; do
  if [ ! -f "$file" ]; then
    echo "$0: $file is missing (build with cargo build --release -p dvrk-model-c)" >&2
    exit 1
  fi
done

mkdir -p "$prefix/lib/pkgconfig" "$prefix/lib/cmake/dvrk_model" "$prefix/include"
prefix=$(cd "$prefix" && pwd)
cp "$libdir/$shared" "$libdir/libdvrk_model_c.a" "$prefix/lib/"
cp "$here/include/dvrk_model.h" "$here/include/dvrk_model.hpp" "$prefix/include/"
sed -e "s|@PREFIX@|$prefix|g" -e "s|@VERSION@|$version|g" "$here/dvrk_model.pc.in" \
  >"$prefix/lib/pkgconfig/dvrk_model.pc"
cp "$here/cmake/dvrk_modelConfig.cmake" "$prefix/lib/cmake/dvrk_model/"
sed -e "s|@VERSION@|$version|g" "$here/cmake/dvrk_modelConfigVersion.cmake.in" \
  >"$prefix/lib/cmake/dvrk_model/dvrk_modelConfigVersion.cmake"
echo "installed dvrk_model $version into $prefix"
