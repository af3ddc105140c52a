#!/usr/bin/env bash
# Round-trip check of the mesh writers against meshio: writes every format with the
# `write_formats` example, then reads each file back with meshio 5.3.5 and compares exactly
# (scripts/meshio_roundtrip.py).
#
# Usage: bash scripts/meshio_roundtrip.sh
#
# Environment:
#   MESHIO_VENV  virtual environment to create/reuse (default: <repo>/.venv-meshio, gitignored)
#   PYTHON       interpreter that creates it (default: python3)
#
# Needs Rust, Python 3 with the venv module, and pip access to PyPI on first use. Any failure
# to set up Python or install the packages is an error (exit non-zero): this check never skips.
set -euo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${MESHIO_VENV:-$ROOT/.venv-meshio}"
PYTHON="${PYTHON:-python3}"
# meshio 5.3.5's readers work with numpy 2 (its ascii Gmsh *writer* does not, but we only
# read). h5py: meshio's XDMF reader imports it for every DataItem, even inline XML ones.
PACKAGES=(meshio==5.3.5 numpy==2.2.6 h5py==3.13.0)

fail() {
    echo "meshio_roundtrip: $*" >&2
    exit 1
}

command -v "$PYTHON" >/dev/null || fail "no '$PYTHON' on PATH (set PYTHON=...)"
if ! "$VENV/bin/python" -c 'import sys' >/dev/null 2>&1; then
    echo "meshio_roundtrip: creating virtual environment $VENV" >&2
    rm -rf "$VENV"
    "$PYTHON" -m venv "$VENV" || fail "could not create a virtual environment with '$PYTHON -m venv'"
fi
VPY="$VENV/bin/python"
"$VPY" -m pip install --disable-pip-version-check --quiet "${PACKAGES[@]}" \
    || fail "pip could not install ${PACKAGES[*]} into $VENV"
"$VPY" - <<'EOF' || fail "the installed packages do not import as expected"
import h5py, meshio, numpy
assert meshio.__version__ == "5.3.5", meshio.__version__
EOF

OUT="$(mktemp -d "${TMPDIR:-/tmp}/meshio_roundtrip.XXXXXX")"
cargo run --release --quiet --manifest-path "$ROOT/Cargo.toml" -p meshes \
    --example write_formats -- "$OUT" \
    || fail "the write_formats example failed (output in $OUT)"
if "$VPY" "$ROOT/scripts/meshio_roundtrip.py" "$OUT"; then
    rm -rf "$OUT"
else
    fail "mismatch; the written files are kept in $OUT"
fi
