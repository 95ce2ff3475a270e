#!/usr/bin/env bash
# Installs every build and test dependency of OpenPhaco from Debian packages.
# Idempotent and non-interactive: safe to run again; does nothing when all is installed.
set -euo pipefail

packages=(
  build-essential cmake ninja-build pkg-config
  clang-format           # the layout scripts/test.sh checks (.clang-format)
  libeigen3-dev          # linear algebra, eigen-solvers, CG
  libtbb-dev             # oneTBB: task graph, parallel_for
  libbullet-dev          # btDbvt broadphase, btSoftBody peer
  libccd-dev             # GJK/MPR narrowphase
  libopencv-dev          # charts, image metrics
  libtet1.5-dev          # TetGen (lens tetrahedralisation)
  nlohmann-json3-dev     # scenario / report JSON
  libsqlite3-dev         # session records
  libpq-dev              # a training centre's records on PostgreSQL (issue 21)
  postgresql             # the throwaway server the records tests run against (scripts/test.sh)
  libgtest-dev libgmock-dev
  libbenchmark-dev       # Google Benchmark
  libglfw3-dev libepoxy-dev libimgui-dev   # trainer (later issues)
  xvfb mesa-utils libgl1-mesa-dri   # renderer tests: a virtual X display, Mesa's llvmpipe
  chromium               # headless check of the HTML report
  fonts-dejavu-core      # the trainer panels' font: range and unit signs (≥ – °) (issue 24)
  xdotool                # the trainer driven as a trainee would: synthetic pointer and keys (issue 24)
  dpkg-dev lintian desktop-file-utils help2man   # the Debian package and its checks (issue 23)
  strace                 # scripts/check-package.sh: the unpacked programs never open the source tree
)

# Node.js and npm run the xAPI validator of the records tests (an npm package, issue 21). A
# machine that has them from elsewhere (NodeSource's nodejs bundles npm) keeps its own: Debian's
# npm package would conflict with it.
if ! command -v node >/dev/null || ! command -v npm >/dev/null; then packages+=(nodejs npm); fi

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
echo "install-deps: installing ${missing[*]}"
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
