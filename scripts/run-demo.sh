#!/usr/bin/env bash
# The README's first command: installs what is needed, builds, and runs the main job —
# the scripted capsulorhexis scenario, headless, printing its report.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
"$root/scripts/install-deps.sh"
PHACO_BUILD_DIR="$root/build/release" "$root/scripts/build.sh"
exec "$root/build/release/apps/phaco" run "$root/data/scenarios/capsulorhexis_demo.json" \
  --report "$root/build/release/capsulorhexis_demo.report.json" "$@"
