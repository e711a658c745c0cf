#!/usr/bin/env bash
# One entry point for a fresh Debian machine:
#   bash scripts/run.sh demo   install what is missing, build, run `orchard demo`
#   bash scripts/run.sh test   install what is missing, build, run the test suite
#   bash scripts/run.sh build  install what is missing, build
#   bash scripts/run.sh sanitize  the test suite under AddressSanitizer and
#                              UndefinedBehaviorSanitizer (its own build folder)
# Installing needs root (apt-get); nothing is installed when all is there.
set -euo pipefail
cd "$(dirname "$0")/.."
what="${1:-build}"
jobs="${ORCHARD_JOBS:-$(nproc)}"

missing=()
while read -r pkg; do
  [[ -z "$pkg" || "$pkg" == \#* ]] && continue
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || missing+=("$pkg")
done < scripts/debian-packages.txt
if [ ${#missing[@]} -gt 0 ]; then
  echo "Installing missing Debian packages: ${missing[*]}"
  sudo_cmd=""
  [ "$(id -u)" -ne 0 ] && sudo_cmd="sudo"
  $sudo_cmd apt-get update -q
  DEBIAN_FRONTEND=noninteractive $sudo_cmd apt-get install -y -q --no-install-recommends "${missing[@]}"
fi

if [ "$what" = sanitize ]; then
  # A memory error or undefined behaviour stops the test that hits it.
  # LibTorch is not instrumented: leak and container-overflow checks are off
  # (they report its allocations). Builds in about 45 min on 2 cores; the suite
  # takes about 6x its usual time.
  dir="${ORCHARD_SANITIZE_DIR:-build-sanitize}"
  cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DCMAKE_CXX_FLAGS="-fsanitize=address,undefined -fno-omit-frame-pointer -O1" \
    -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" >/dev/null
  cmake --build "$dir" -j "$jobs"
  ASAN_OPTIONS=detect_leaks=0:detect_container_overflow=0 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    ctest --test-dir "$dir" --output-on-failure -j "$jobs" --timeout 1800
  exit
fi

cmake -S . -B build -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build build -j "$jobs"

case "$what" in
  build) ;;
  demo) ./build/orchard demo --out build/demo ;;
  test) ctest --test-dir build --output-on-failure -j "$jobs" ;;
  *) echo "usage: bash scripts/run.sh [demo|test|build|sanitize]" >&2; exit 2 ;;
esac
