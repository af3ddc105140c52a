#!/usr/bin/env bash
# Runs every bundled scene with a memstab binary and compares the outputs with those of an
# earlier run: `scripts/same_outputs.sh record DIR` writes them into DIR,
# `scripts/same_outputs.sh check DIR` runs again and compares path.csv and critical.json
# byte for byte (and reports whether path.json differs). Use the same machine and thread
# count for both: parallel sums make the last bits depend on the number of threads.
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
for scene in scenes/*.toml; do
  name=$(basename "$scene" .toml)
  "$bin" run "$scene" --out "$target/$name" --quiet > "$target/$name.txt"
  if [ "$mode" = check ]; then
    for f in path.csv critical.json; do
      if ! cmp -s "$dir/$name/$f" "$target/$name/$f"; then
        echo "DIFFERENT: $name/$f"; status=1
      fi
    done
    cmp -s "$dir/$name/path.json" "$target/$name/path.json" || echo "note: $name/path.json differs"
  fi
done
[ "$mode" = check ] && [ $status = 0 ] && echo "path.csv and critical.json identical for every bundled scene"
exit $status
