#!/usr/bin/env bash
# The Python package (python/): its abi3 wheel built with maturin in a virtual environment
# (maturin, numpy, pandas, meshio, scipy, pytest and matplotlib from PyPI, and for the tests
# of the optional parts tqdm, pyarrow, pyvista and the continuation package bice), installed there,
# its tests run (pytest: real runs on small meshes), and the study blocks of docs/python.md
# (between `<!-- study -->` and `<!-- /study -->`) run as one script, as a reader would from
# the repository's root.
#
# Usage: scripts/python_package.sh [VENV]   (default VENV: .venv-python; made if missing)
set -euo pipefail
cd "$(dirname "$0")/.."
root="$PWD"
venv="${1:-.venv-python}"
[ -x "$venv/bin/python" ] || python3 -m venv "$venv"
venv="$(cd "$venv" && pwd)"
"$venv/bin/pip" install --quiet --upgrade pip
"$venv/bin/pip" install --quiet maturin numpy pandas meshio scipy pytest matplotlib tqdm pyarrow bice
# pyvista for `state(i, pyvista=True)`: the versions scripts/requirements.txt pins, which the
# round-trip check has downloaded already.
"$venv/bin/pip" install --quiet "$(grep -o '^pyvista==[0-9.]*' scripts/requirements.txt)" \
    "$(grep -o '^vtk==[0-9.]*' scripts/requirements.txt)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

# The wheel, built in the repository's target directory (the dependencies compiled for the
# binary are not shared: the native module's workspace resolves and builds its own).
CARGO_TARGET_DIR="$root/target" "$venv/bin/maturin" build --release --quiet \
    --manifest-path python/Cargo.toml --out "$work/wheels"
"$venv/bin/pip" install --quiet --force-reinstall "$work"/wheels/memstab-*.whl
"$venv/bin/python" -c 'import memstab; print("memstab", memstab.__version__, "from", memstab.__file__)'

"$venv/bin/pytest" -q python/tests

awk '/^<!-- study -->$/{on=1; next} /^<!-- \/study -->$/{on=0} on && !/^```/' docs/python.md \
    > "$work/study.py"
[ -s "$work/study.py" ] || { echo "error: no study block in docs/python.md" >&2; exit 1; }
mkdir "$work/study"
ln -s "$root/scenes" "$work/study/scenes"
(cd "$work/study" && MPLBACKEND=Agg "$venv/bin/python" ../study.py)
[ -s "$work/study/paper1_k.png" ] || { echo "error: the study wrote no paper1_k.png" >&2; exit 1; }
echo "docs/python.md: its study ran as a script and wrote paper1_k.png"
