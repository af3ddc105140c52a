#!/usr/bin/env bash
# Renders the figures of docs/thesis.md from memstab's own runs into docs/figures/ (PNG),
# with scripts/thesis_figures.py (matplotlib and meshio), on the thesis's mesh sizes: the disc's
# 1 792 triangles, the f = 16 icosphere, the caps' 5 408 triangles. About five minutes on
# 2 cores after the release build; QUICK=1 takes under a minute.
#
# Usage: bash scripts/thesis_figures.sh
#
# Environment:
#   MEMSTAB      the memstab binary (default: built here with cargo build --release)
#   MESHIO_VENV  virtual environment to create/reuse (default: <repo>/.venv-meshio, gitignored)
#   PYTHON       interpreter that creates it (default: python3)
#   OUT          where the runs are written (default: <repo>/target/thesis-figures)
#   FIGURES      where the PNG figures go (default: <repo>/docs/figures)
#   QUICK        1: the bundled scenes' smaller meshes where they differ from the thesis's
#                (the swallowtail on 448 triangles, Paper 2 on f = 8, the caps on 1 152
#                triangles): CI's form, a check that every figure still draws.
#
# Each figure is checked before it is written (no two labels overlap, none lies on a legend or
# an inset); the script fails naming the figure and the labels otherwise.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${MESHIO_VENV:-$ROOT/.venv-meshio}"
PYTHON="${PYTHON:-python3}"
OUT="${OUT:-$ROOT/target/thesis-figures}"
FIGURES="${FIGURES:-$ROOT/docs/figures}"
PACKAGES=(meshio==5.3.5 numpy==2.2.6 matplotlib==3.11.2)

fail() {
    echo "thesis_figures: $*" >&2
    exit 1
}

if [ -z "${MEMSTAB:-}" ]; then
    cargo build --release --quiet --manifest-path "$ROOT/Cargo.toml" || fail "the release build failed"
    MEMSTAB="$ROOT/target/release/memstab"
fi
command -v "$PYTHON" >/dev/null || fail "no '$PYTHON' on PATH (set PYTHON=...)"
if ! "$VENV/bin/python" -c 'import sys' >/dev/null 2>&1; then
    rm -rf "$VENV"
    "$PYTHON" -m venv "$VENV" || fail "could not create a virtual environment with '$PYTHON -m venv'"
fi
"$VENV/bin/python" -m pip install --disable-pip-version-check --quiet "${PACKAGES[@]}" \
    || fail "pip could not install ${PACKAGES[*]} into $VENV"
"$VENV/bin/python" "$ROOT/scripts/thesis_figures.py" "$MEMSTAB" "$OUT" "$FIGURES"
echo "thesis_figures: figures in $FIGURES, runs in $OUT"
