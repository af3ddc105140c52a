#!/usr/bin/env bash
# Runs every bundled scene with a memstab binary and compares the outputs with those of an
# earlier run: `scripts/same_outputs.sh record DIR` writes them into DIR,
# `scripts/same_outputs.sh check DIR` runs again and compares path.csv, critical.json and
# path.json byte for byte. The bundled 3-D scenes (scenes/*.toml and scenes/thesis/*.toml)
# are compared; the axisymmetric ones (scenes/axisymmetric/*.toml) are run and their files
# listed, since a meridian run's layout may grow. Use the same machine and thread count for
# both: parallel sums make the last bits depend on the number of threads.
set -euo pipefail
cd "$(dirname "$0")/.."
mode=${1:?usage: same_outputs.sh record|check DIR}
dir=${2:?usage: same_outputs.sh record|check DIR}
bin=${MEMSTAB:-target/release/memstab}
case "$mode" in
  record) target=$dir ;;
  check) target=$(mktemp -d) ;;
  *) echo "usage: same_outputs.sh record|check DIR" >&2; exit 2 ;;
esac
mkdir -p "$target"
status=0
for scene in scenes/*.toml scenes/thesis/*.toml scenes/axisymmetric/*.toml; do
  name=$(basename "$(dirname "$scene")")_$(basename "$scene" .toml)
  "$bin" run "$scene" --out "$target/$name" --quiet > "$target/$name.txt"
  case "$scene" in scenes/axisymmetric/*) continue ;; esac
  if [ "$mode" = check ]; then
    for f in path.csv critical.json path.json; do
      if ! cmp -s "$dir/$name/$f" "$target/$name/$f"; then
        echo "DIFFERENT: $name/$f"; status=1
      fi
    done
  fi
done
[ "$mode" = check ] && [ $status = 0 ] && echo "path.csv, critical.json and path.json identical for every bundled 3-D scene"
exit $status
