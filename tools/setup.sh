#!/usr/bin/env bash
# Set up hsgran on a fresh Debian machine: a virtual environment in .venv with the package, its
# test tools and the rendering extra (pyvista, vtk, imageio, matplotlib), plus the system GL
# libraries that offscreen VTK needs (DESIGN.md §6). Safe to run again: each step is skipped or
# is a no-op when already done.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}

# Offscreen VTK loads libEGL and a Mesa driver at run time; without them it segfaults instead of
# raising, so they are installed here rather than discovered by a crash.
GL_PACKAGES="libegl1 libgl1-mesa-dri"
missing=""
for pkg in $GL_PACKAGES; do
    if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $pkg"
    fi
done
if [ -n "$missing" ]; then
    if [ "$(id -u)" -eq 0 ] && command -v apt-get >/dev/null; then
        echo "installing system libraries for offscreen rendering:$missing"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends $missing
    else
        echo "skipping system libraries for rendering (not root or no apt-get); to render," \
             "install them as root: apt-get install -y --no-install-recommends$missing"
    fi
fi

if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e '.[dev,render,export]'
# Compile the event loop now, its versions side by side (a few minutes; seconds when the cache
# has them already), rather than in the first run that needs each one.
.venv/bin/hsgran compile
echo "hsgran is set up in .venv (try: .venv/bin/hsgran --help)"
