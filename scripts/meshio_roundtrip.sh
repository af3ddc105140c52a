#!/usr/bin/env bash
# Round-trip check of the mesh writers against meshio: writes every format with the
# `write_formats` example, then reads each file back with meshio 5.3.5 and compares exactly
# (scripts/meshio_roundtrip.py), and the surface.vtu of a balloon surface against its
# surface.json. Then runs the balloon (scenes/balloon.toml at icosphere
# frequency 4), reads every state of its two collections back with meshio and checks the
# fields against the closed-form tension and thickness (scripts/state_fields_check.py), and
# runs the Python block of docs/python.md on that run.
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
# pandas and matplotlib: the block of docs/python.md.
# pyvista (with its vtk): state_fields_check.py reads a state with it and tries an off-screen
# screenshot, which it skips where the machine has no OpenGL library.
PACKAGES=(meshio==5.3.5 numpy==2.2.6 h5py==3.13.0 pandas==3.1.1 matplotlib==3.11.2 pyvista==0.49.2 vtk==9.7.2)

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
import h5py, matplotlib, meshio, numpy, pandas, pyvista
assert meshio.__version__ == "5.3.5", meshio.__version__
EOF

OUT="$(mktemp -d "${TMPDIR:-/tmp}/meshio_roundtrip.XXXXXX")"
cargo run --release --quiet --manifest-path "$ROOT/Cargo.toml" -p meshes \
    --example write_formats -- "$OUT" \
    || fail "the write_formats example failed (output in $OUT)"

# An equilibrium surface: the balloon at frequency 4 with k as a parameter, three paths in p
# at k = 0.05 ... 0.2; its surface.vtu is checked against its surface.json.
"$VPY" - "$ROOT/scenes/balloon.toml" "$OUT/surface.toml" <<'EOF' || fail "could not write the surface scene"
import sys
text = open(sys.argv[1]).read()
analysis, start = text.index("[analysis]"), text.index("[start]")
surface = """[parameters.k]
start = 0.1

[analysis]
type = "surface"
parameters = ["p", "k"]
ranges = [[0.0, 2.0], [0.05, 0.2]]
paths = 3
steps = 60
max-step = 0.1
measure = "stretch"

"""
text = text[:analysis] + surface + text[start:]
text = text.replace("k = 0.1\n", 'k = "k"\n', 1).replace("frequency = 8", "frequency = 4", 1)
assert 'k = "k"' in text and "frequency = 4" in text
open(sys.argv[2], "w").write(text)
EOF
cargo run --release --quiet --manifest-path "$ROOT/Cargo.toml" -- \
    run "$OUT/surface.toml" --out "$OUT/surface-out" --quiet >/dev/null \
    || fail "memstab run on the balloon surface failed (output in $OUT)"
if ! "$VPY" "$ROOT/scripts/meshio_roundtrip.py" "$OUT" --surface "$OUT/surface-out"; then
    fail "mismatch; the written files are kept in $OUT"
fi

# The states of a run, read back: the balloon at frequency 4 (162 nodes) through both
# turning points.
sed 's/^frequency = 8 .*/frequency = 4/' "$ROOT/scenes/balloon.toml" >"$OUT/balloon.toml"
grep -q '^frequency = 4$' "$OUT/balloon.toml" || fail "could not set the balloon's frequency"
cargo run --release --quiet --manifest-path "$ROOT/Cargo.toml" -- \
    run "$OUT/balloon.toml" --out "$OUT/balloon-out" --quiet >/dev/null \
    || fail "memstab run on the balloon failed (output in $OUT)"
"$VPY" "$ROOT/scripts/state_fields_check.py" "$OUT/balloon-out" \
    || fail "the balloon's state fields do not match; the run is kept in $OUT/balloon-out"

# docs/python.md's Python block, as a reader would paste it, beside the run.
awk '/^```python$/{on=1; next} /^```$/{on=0} on' "$ROOT/docs/python.md" >"$OUT/python_md.py"
[ -s "$OUT/python_md.py" ] || fail "no python block in docs/python.md"
(cd "$OUT" && MPLBACKEND=Agg "$VPY" python_md.py >/dev/null) \
    || fail "the block of docs/python.md failed on $OUT/balloon-out"
[ -s "$OUT/balloon-out/branch.png" ] || fail "docs/python.md's block wrote no branch.png"
echo "docs/python.md: its block ran on the balloon run and wrote branch.png"
rm -rf "$OUT"
