#!/usr/bin/env bash
# The README's second command (and what .ci/run calls): installs what is needed, checks every C++
# file against .clang-format, builds, starts a throwaway PostgreSQL server and the xAPI validator
# for the records tests, and runs every test, the perf harness's quick sweep and soak, and checks the
# Debian package (scripts/check-package.sh); then builds the ASan+UBSan configuration and runs every test again under it
# (skip that with PHACO_SKIP_SANITIZERS=1 for a quick local run), and the haptic tests (the 1 kHz
# loop, the lock-free handoff, the devices, the session) under ThreadSanitizer. TSan runs only those:
# Debian's libtbb is not instrumented, so TSan would report oneTBB's own hand-offs as races, and
# the haptic path is built without oneTBB.
# All three builds are unity builds (PHACO_UNITY_BUILD, CMakeLists.txt: each target's files
# compiled in batches of 8), which costs less CPU from scratch; the Release tests run on that
# build. What every phase costs on 2 cores: docs/install.md ("What the CI run costs").
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="${PHACO_JOBS:-$(nproc)}"
# Each phase's wall time, printed as it ends, so a run's log shows where the 45 minutes go.
phase_start=$SECONDS
phase() { echo "test.sh: $1 took $((SECONDS - phase_start)) s (${SECONDS} s in all)"; phase_start=$SECONDS; }
"$root/scripts/install-deps.sh"
phase "installing the dependencies"

# Formatting (issue 22): every C++ file as the project's .clang-format (Debian's clang-format)
# lays it out; any file that differs fails the run, named, before anything is built.
# The tracked files, or every source file where the tree is not a git checkout (a tarball).
sources() {
  git -C "$root" ls-files '*.cpp' '*.hpp' 2>/dev/null ||
    (cd "$root" && find apps components engine perf procedures systems tests -name '*.[ch]pp')
}
# One clang-format process per 100 files (--dry-run -Werror reports each differing file by name):
# a process per file spent ~1.5 CPU minutes loading clang-format 675 times, this ~4 s.
format_log="$(mktemp)"
if ! (cd "$root" && sources | xargs -r -n 100 -P "$jobs" clang-format --style=file --dry-run -Werror) \
  >/dev/null 2>"$format_log"; then
  unformatted="$(sed -n 's/^\(.*\):[0-9]*:[0-9]*: error: code should be clang-formatted.*/\1/p' \
    "$format_log" | sort -u)"
  echo "test.sh: these files differ from .clang-format (run clang-format -i on them):" >&2
  if [ -n "$unformatted" ]; then echo "$unformatted" >&2; else cat "$format_log" >&2; fi
  exit 1
fi
rm -f "$format_log"
phase "the format check"

build="$root/build/release"
PHACO_BUILD_DIR="$build" "$root/scripts/build.sh" -DPHACO_UNITY_BUILD=ON
phase "the Release build"
# The xAPI validator the records tests run (issue 21): Learning Locker's, from npm, at the
# version tests/tools/xapi/package-lock.json pins, installed into the build tree.
mkdir -p "$build/xapi-validator"
cp "$root/tests/tools/xapi/package.json" "$root/tests/tools/xapi/package-lock.json" \
  "$root/tests/tools/xapi/validate.js" "$build/xapi-validator/"
(cd "$build/xapi-validator" && npm ci --no-audit --no-fund --loglevel=error >/dev/null)
export PHACO_XAPI_VALIDATOR="$build/xapi-validator/validate.js"
# A throwaway PostgreSQL server for the records tests (issue 21): its own folder, a Unix socket
# there, removed when this script ends, pass or fail (scripts/pg_test_cluster.sh).
pg_dir="$(mktemp -d "${TMPDIR:-/tmp}/phaco-pg.XXXXXX")"  # empty: the cluster is made in it
trap '"$root/scripts/pg_test_cluster.sh" remove "$pg_dir"' EXIT
eval "$("$root/scripts/pg_test_cluster.sh" start "$pg_dir")"
export PHACO_TEST_PG_URI PHACO_TEST_PG_DIR PHACO_TEST_PG_CTL
# Tests build their meshes into a cache inside the build tree, never into the user's home.
export PHACO_CACHE_DIR="$build/mesh-cache"
# A test that needs an X server, GL or xvfb-run fails here instead of skipping: this run must not
# pass on a machine where the renderer and the trainer never ran (tests/support/environment.hpp).
export PHACO_TEST_STRICT=1
ctest --test-dir "$build" --output-on-failure -j "$jobs"
phase "the xAPI validator, PostgreSQL and the Release tests"
# The perf harness's quick sweep (issue 9): every drill at levels 0..3 and each method alternative,
# each point in its own process. It fails the run if a point does not run to its end, if 1 and 2
# threads give different state hashes, or if the default methods diverge or leave their accuracy
# bounds. Speed is reported (in build/release/perf-quick/RESULTS.md), never checked here.
"$build/perf/phaco-perf" sweep --quick --out-dir "$build/perf-quick"
phase "the quick sweep"
# The trainer left running drill after drill for 90 s under Xvfb (issue 18): fails the run if its
# memory grows more than 5 % after the first round of drills or a drill leaks GL objects.
"$build/perf/phaco-perf" soak --quick --out-dir "$build/perf-quick"
phase "the quick soak"
# The Debian package (issue 23), made from this build tree, then checked as a trainee's PC gets it:
# lintian, the desktop entry, and the unpacked programs run from an empty folder, finding their
# data in the package and never opening the source tree (scripts/check-package.sh).
"$root/scripts/check-package.sh" "$(PHACO_BUILD_DIR="$build" "$root/scripts/package.sh")"
phase "the package and its check"

if [ "${PHACO_SKIP_SANITIZERS:-0}" != "1" ]; then
  asan="$root/build/asan"
  # -O1 with line tables (-g1): what the ASan documentation suggests, and a third of the compile
  # time of -O2 -g on the Eigen-heavy files (shape_match's Horn solvers: 140 s at -O2 -g).
  cmake -S "$root" -B "$asan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHACO_SANITIZE=address \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DPHACO_BUILD_BENCHMARKS=OFF -DPHACO_UNITY_BUILD=ON >/dev/null
  # Only what the tests run (every test executable and the phaco CLI), not the perf harness.
  cmake --build "$asan" -j "$jobs" --target phaco_tests
  phase "the ASan build"
  PHACO_CACHE_DIR="$asan/mesh-cache" ctest --test-dir "$asan" --output-on-failure -j "$jobs"
  phase "the ASan tests"
fi

if [ "${PHACO_SKIP_SANITIZERS:-0}" != "1" ]; then
  tsan="$root/build/tsan"
  cmake -S "$root" -B "$tsan" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DPHACO_SANITIZE=thread \
    -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" -DCMAKE_C_FLAGS_RELWITHDEBINFO="-O1 -g1 -DNDEBUG" \
    -DPHACO_BUILD_BENCHMARKS=OFF -DPHACO_UNITY_BUILD=ON >/dev/null
  haptic_tests=(engine/haptics/test_haptic_loop engine/haptics_devices/test_haptics_devices
                procedures/haptics/test_haptic_session)
  cmake --build "$tsan" -j "$jobs" --target "${haptic_tests[@]##*/}"
  # halt_on_error: a reported race fails the run (TSan otherwise only sets the exit code at exit).
  for t in "${haptic_tests[@]}"; do
    TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" "$tsan/tests/$t"
  done
  phase "the TSan build and tests"
fi
