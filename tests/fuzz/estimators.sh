#!/usr/bin/env bash
# libFuzzer on the C++ estimators (tests/cpp/fuzz_estimators.cpp): build with clang under
# AddressSanitizer and UndefinedBehaviorSanitizer, then fuzz; the arguments go to libFuzzer.
#   bash tests/fuzz/estimators.sh                          # one minute
#   bash tests/fuzz/estimators.sh -max_total_time=3600     # an hour
# Needs clang with its libFuzzer runtime (Debian: apt-get install clang) and cmake. The corpus
# grows in build/fuzz/estimators; findings are build/fuzz/estimators-crash-* (replay: pass the
# file instead of the options).
set -euo pipefail
cd "$(dirname "$0")/../.."
build=build/fuzz-cpp
cmake -S . -B "$build" -DCMAKE_CXX_COMPILER="${CXX:-clang++}" -DCMAKE_BUILD_TYPE=Debug \
  -DALGID_BUILD_TESTS=ON -DALGID_BUILD_FUZZ=ON -DALGID_BUILD_PYTHON=OFF \
  -DPython_EXECUTABLE="$(command -v "${PYTHON:-python3}")" >/dev/null
cmake --build "$build" --target fuzz_estimators -j 1
mkdir -p build/fuzz/estimators
if [ "$#" -eq 0 ]; then set -- -max_total_time=60; fi
case "$1" in
  -*) exec "$build/tests/cpp/fuzz_estimators" -artifact_prefix=build/fuzz/estimators- "$@" build/fuzz/estimators ;;
  *) exec "$build/tests/cpp/fuzz_estimators" "$@" ;;
esac
