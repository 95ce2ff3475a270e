#!/usr/bin/env bash
# The README's first command: installs what is needed, builds, and runs the main job. Where a
# display exists (DISPLAY or WAYLAND_DISPLAY set) that is the trainer, phaco-trainer, on the
# capsulorhexis drill with mouse and keyboard (arguments are passed to it, e.g. --drill
# phaco_sculpting). Where none does (a server, CI, a container) it is the headless demo: the
# scripted capsulorhexis scenario run by `phaco run`, printing its report, then the report as an
# HTML page. PHACO_HEADLESS=1 forces the headless demo.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install-deps.sh"
PHACO_BUILD_DIR="$root/build/release" "$root/scripts/build.sh"
build="$root/build/release"
if [ "${PHACO_HEADLESS:-0}" != "1" ] && { [ -n "${DISPLAY:-}" ] || [ -n "${WAYLAND_DISPLAY:-}" ]; }; then
  exec "$build/apps/phaco-trainer" "$@"
fi
echo "No display: running the headless demo (phaco-trainer needs one; see README)." >&2
"$build/apps/phaco" run "$root/data/scenarios/capsulorhexis_demo.json" \
  --report "$build/capsulorhexis_demo.report.json"
exec "$build/apps/phaco" report "$build/capsulorhexis_demo.report.json" \
  --html "$build/capsulorhexis_demo.report.html"
