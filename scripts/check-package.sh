#!/usr/bin/env bash
# Checks the Debian package as a trainee's PC would get it (issue 23; scripts/test.sh runs it):
# lintian reports no error and the desktop entry validates; unpacked with `dpkg -x` into a
# temporary root and run from an empty folder with PHACO_DATA_DIR unset and a fresh home, the
# programs find their data in the unpacked share/openphaco, every installed scenario validates,
# `phaco run` runs one to its end (writing its mesh cache in $XDG_CACHE_HOME), phaco-trainer
# answers --help and saves one screenshot under Xvfb; and under strace no file below the source
# tree (or the build tree) is ever opened: the source tree might as well be gone.
# Usage: scripts/check-package.sh PACKAGE.deb
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
deb="$(realpath "$1")"
fail() { echo "check-package: $*" >&2; exit 1; }

lintian --fail-on error "$deb" || fail "lintian reports errors for $deb"

tmp="$(mktemp -d "${TMPDIR:-/tmp}/phaco-pkg.XXXXXX")"
trap 'rm -rf "$tmp"' EXIT
pkg="$tmp/root" && mkdir -p "$pkg" "$tmp/home" "$tmp/run"
dpkg -x "$deb" "$pkg"
desktop-file-validate "$pkg/usr/share/applications/openphaco.desktop" || fail "desktop entry"
[ -s "$pkg/usr/share/icons/hicolor/scalable/apps/openphaco.svg" ] || fail "no icon"
share="$pkg/usr/share/openphaco"

# The unpacked programs, alone: no PHACO_* variable, a fresh home (XDG defaults below it).
in_pkg() {
  (cd "$tmp/run" && env -u PHACO_DATA_DIR -u PHACO_CACHE_DIR -u PHACO_DB -u PHACO_RECORDS_DB \
    -u XDG_CACHE_HOME -u XDG_DATA_HOME -u XDG_CONFIG_HOME HOME="$tmp/home" \
    PATH="$pkg/usr/bin:/usr/bin:/bin" "$@")
}
version="$(in_pkg phaco --version)"
echo "$version"
grep -qx "data: $share (installed)" <<<"$version" || fail "phaco does not use $share"
in_pkg phaco-trainer --version | grep -qx "data: $share (installed)" ||
  fail "phaco-trainer does not use $share"
in_pkg phaco-trainer --help >/dev/null || fail "phaco-trainer --help"
in_pkg phaco validate "$share"/scenarios/*.json >/dev/null || fail "an installed scenario does not validate"

# One short scenario to its end and a screenshot, traced: every file either opens.
in_pkg strace -f -qq -e trace=%file -o "$tmp/run.trace" \
  phaco run "$share/scenarios/corneal_incision_expert.json" --report "$tmp/run/report.json" >/dev/null ||
  fail "phaco run on an installed scenario"
[ -n "$(ls -A "$tmp/home/.cache/openphaco/meshes")" ] || fail "no mesh cache in ~/.cache/openphaco"
in_pkg strace -f -qq -e trace=%file -o "$tmp/trainer.trace" \
  xvfb-run -a -s "-screen 0 1280x800x24" phaco-trainer --drill corneal_incision --size 640x400 \
  --screenshot "$tmp/run/shot.png" --after 0.5 >/dev/null || fail "phaco-trainer --screenshot"
[ "$(head -c 8 "$tmp/run/shot.png" | od -An -tx1 | tr -d ' \n')" = 89504e470d0a1a0a ] ||
  fail "the screenshot is not a PNG"
if grep -h "\"$root/" "$tmp/run.trace" "$tmp/trainer.trace"; then
  fail "the unpacked programs touched the source tree $root (above)"
fi
grep -q "$share/eye/standard_eye.json" "$tmp/run.trace" || fail "the trace shows no data read from $share"
echo "check-package: $(basename "$deb") passes (lintian, desktop entry, run, trainer, no source tree)"
