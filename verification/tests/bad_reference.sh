#!/bin/sh
# Writes a corrupted copy of an accepted reference and gates the case against it.
# Usage: bad_reference.sh MODE VERIFY REFERENCE_DIR CASE, MODE one of nan-value, inf-tolerance,
# duplicate, kind, misspelt-tolerance, figure-tolerance, scalar-tolerance. The gate must refuse the file (exit 2) naming the problem and the line.
mode=$1 verify=$2 ref=$3 case=$4
dir=$(mktemp -d) || exit 3
trap 'rm -rf "$dir"' EXIT
src="$ref/$case.toml"
dst="$dir/$case.toml"
case $mode in
  nan-value) sed '0,/^value = .*/s//value = nan/' "$src" > "$dst" ;;
  inf-tolerance) sed 's/^error_rel = .*/error_rel = inf/' "$src" > "$dst" ;;
  duplicate) { cat "$src"; awk '/^\[\[figure\]\]/{n++} n==1' "$src"; } > "$dst" ;;
  kind) awk '/^kind = "order"/ && !done {print "kind = \"error\""; done=1; next} {print}' "$src" > "$dst" ;;
  misspelt-tolerance) sed 's/^error_rel = /eror_rel = /' "$src" > "$dst" ;;
  figure-tolerance) awk '/^value = / && !done {print; print "error_rel = 10"; done=1; next} {print}' "$src" > "$dst" ;;
  scalar-tolerance) awk '/^\[tolerance\]/{skip=1; print "tolerance = 0.0"; next} skip && /^$/{skip=0} !skip' "$src" > "$dst" ;;
  *) echo "bad_reference.sh: unknown mode $mode"; exit 3 ;;
esac
"$verify" gate --case "$case" --reference "$dir"
