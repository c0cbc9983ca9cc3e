#!/bin/sh
# Installs the build tree BUILD into a fresh prefix, then configures, builds and runs the consumer
# project against it with find_package(liquid). Usage: check.sh BUILD_DIR SOURCE_DIR
set -e
prefix=$(mktemp -d)
trap 'rm -rf "$prefix"' EXIT
cmake --install "$1" --prefix "$prefix" > "$prefix/install.log"
cmake -S "$2/cmake/consumer" -B "$prefix/build" -DCMAKE_PREFIX_PATH="$prefix" -DCMAKE_BUILD_TYPE=Release > "$prefix/configure.log"
cmake --build "$prefix/build" -j2 > "$prefix/build.log" || { cat "$prefix/build.log"; exit 1; }
"$prefix/build/consumer"
