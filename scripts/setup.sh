#!/usr/bin/env bash
# Sets up everything ribbar needs on a fresh Debian machine with a Rust
# toolchain: the system libraries gmsh's wheel links against, a pinned gmsh
# in a project-local virtual environment (.tools/gmsh-venv), and the release
# build of the `ribbar` binary. Idempotent: a second run only checks.
set -euo pipefail
cd "$(dirname "$0")/.."
build=1
[ "${1:-}" = "--no-build" ] && build=0

GMSH_VERSION=4.15.2
VENV=.tools/gmsh-venv

# gmsh's wheel links against X11/GL/fontconfig even when run without a display.
need_pkgs=()
for pkg in libglu1-mesa libgl1 libxrender1 libxcursor1 libxfixes3 libxext6 libxft2 \
           libfontconfig1 libxinerama1 libx11-6 libgomp1 fonts-dejavu-core; do
  dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed" || need_pkgs+=("$pkg")
done
if [ ${#need_pkgs[@]} -gt 0 ]; then
  echo "setup: installing system packages: ${need_pkgs[*]}"
  SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO=sudo
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${need_pkgs[@]}" >/dev/null
fi

if ! "$VENV/bin/python" -c "import gmsh, sys; sys.exit(gmsh.__version__ != '$GMSH_VERSION')" 2>/dev/null; then
  echo "setup: installing gmsh $GMSH_VERSION into $VENV"
  rm -rf "$VENV"
  python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q --disable-pip-version-check "gmsh==$GMSH_VERSION"
fi
echo "setup: gmsh $("$VENV/bin/python" "$VENV/bin/gmsh" --version 2>&1 | tail -1) at $VENV/bin/gmsh"

if [ "$build" = 1 ]; then
  # -p: the root package is the verification suite; a bare build would skip the binary.
  cargo build --release --quiet -p pipeline --bin ribbar
  echo "setup: built target/release/ribbar"
fi
