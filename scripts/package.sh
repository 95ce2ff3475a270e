#!/usr/bin/env bash
# Builds the Debian package build/release/package/openphaco_<version>_amd64.deb from the release
# build tree (configured and built first, a no-op when it is up to date), then prints its path.
# Install it with `sudo apt-get install ./build/release/package/openphaco_*.deb` (docs/install.md).
# Usage: scripts/package.sh [extra cmake -D options...]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${PHACO_BUILD_DIR:-$root/build/release}"
PHACO_BUILD_DIR="$build" "$root/scripts/build.sh" "$@" >&2  # stdout: the package path alone
rm -f "$build"/package/openphaco_*.deb
(cd "$build" && cpack -G DEB --config CPackConfig.cmake >/dev/null)
ls "$build"/package/openphaco_*.deb
