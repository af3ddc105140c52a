#!/usr/bin/env bash
# A 3 x 3 sweep (the upward-loaded disc without its branches, over material.k and
# mesh.divisions) run here by `memstab sweep` and through the Snakefile `memstab sweep --emit
# snakemake` writes, run by snakemake (from PyPI, in a virtual environment) with its local
# executor: the collected tables must be the same, byte for byte.
#
# Usage: scripts/sweep_snakemake.sh [VENV]   (default VENV: .venv-sweep; made if missing)
set -euo pipefail
cd "$(dirname "$0")/.."
venv="${1:-.venv-sweep}"
venv_abs="$(cd "$(dirname "$venv")" && pwd)/$(basename "$venv")"
if [ ! -x "$venv/bin/snakemake" ]; then
    python3 -m venv "$venv"
    "$venv/bin/pip" install --quiet --upgrade pip
    "$venv/bin/pip" install --quiet snakemake
fi
"$venv/bin/snakemake" --version

cargo build --release --quiet
memstab="$PWD/target/release/memstab"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

sed '/^\[analysis\.branches\]/,$d' scenes/disc_upward.toml > "$work/disc.toml"
cat > "$work/grid.toml" <<'TOML'
[sweep]
scene = "disc.toml"
name = "disc-k-divisions"

[grid]
"material.k" = [0.0, 0.05, 0.1]
"mesh.divisions" = [3, 4, 5]
TOML

"$memstab" sweep "$work/grid.toml" --out "$work/local" --quiet
"$memstab" collect "$work/local"

"$memstab" sweep "$work/grid.toml" --out "$work/snake" --emit snakemake
(cd "$work" && "$venv_abs/bin/snakemake" --snakefile snake/Snakefile --cores 2)
"$memstab" collect "$work/snake"

for f in collected.csv collected_runs.csv; do
    if ! cmp "$work/local/$f" "$work/snake/$f"; then
        echo "error: $f differs between the local sweep and the one snakemake ran" >&2
        diff "$work/local/$f" "$work/snake/$f" >&2 || true
        exit 1
    fi
done
rows=$(($(wc -l < "$work/local/collected.csv") - 1))
echo "sweep through snakemake: the same collected table as the local sweep ($rows points of 9 runs)"
