#!/usr/bin/env bash
# Runs every bundled scene with a memstab binary and compares the outputs with those of an
# earlier run: `scripts/same_outputs.sh record DIR` writes them into DIR,
# `scripts/same_outputs.sh check DIR` runs again and compares every file of every run byte for
# byte (path.csv, critical.json, path.json, the states, the curves, surfaces and figures; all
# but the manifest, whose checksums follow from the rest) and the printed summary (but for
# its wall times), for every bundled scene: scenes/*.toml, scenes/thesis/*.toml and the
# meridian's scenes/axisymmetric/*.toml. Use the same machine and thread count for both:
# parallel sums make the last bits depend on the number of threads.
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
  if [ "$mode" = check ]; then
    files=$( (cd "$dir/$name" && find . -type f; cd "$target/$name" && find . -type f) | sort -u | grep -v "manifest.json$")
    # The summary, but for the directory and the wall times.
    if ! cmp -s <(sed -E "s|$dir|DIR|g; s/ in [0-9.]+ m?s/ in T/g" "$dir/$name.txt") \
                <(sed -E "s|$target|DIR|g; s/ in [0-9.]+ m?s/ in T/g" "$target/$name.txt"); then
      echo "DIFFERENT: $name summary"; status=1
    fi
    for f in $files; do
      if ! cmp -s "$dir/$name/$f" "$target/$name/$f"; then
        echo "DIFFERENT: $name/$f"; status=1
      fi
    done
  fi
done
[ "$mode" = check ] && [ $status = 0 ] && echo "every file and summary of every bundled scene's run identical"
exit $status
