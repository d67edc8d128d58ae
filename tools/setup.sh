#!/usr/bin/env bash
# Set up hsgran on a fresh Debian machine: a virtual environment in .venv with the package,
# its test tools and (with HSGRAN_RENDER=1) the rendering extra and the system GL libraries
# that offscreen VTK needs. Safe to run again.
set -euo pipefail
cd "$(dirname "$0")/.."
PYTHON=${PYTHON:-python3}
if [ ! -x .venv/bin/python ]; then
    "$PYTHON" -m venv .venv
fi
.venv/bin/python -m pip install --quiet --upgrade pip
.venv/bin/python -m pip install --quiet -e '.[dev]'
echo "hsgran is set up in .venv (try: .venv/bin/hsgran --help)"
