#!/bin/sh
# A run whose output folder fills up: exit 1 with one message naming the file and "No space left on
# device", no HDF5 diagnostics, no crash, no temporary left behind. The folder is a 200 kB tmpfs,
# which needs root: without it the test reports itself skipped (exit 77).
# Usage: disk_full.sh MODE LIQUID, MODE one of pic-frames, pic-checkpoint, pic-3d-first-frame,
# sph-checkpoint.
mode=$1 liquid=$2
dir=$(mktemp -d) || exit 3
cleanup() { umount "$dir" 2>/dev/null; rm -rf "$dir"; }
trap cleanup EXIT
if ! mount -t tmpfs -o size=200k tmpfs "$dir" 2>/dev/null; then
  echo "disk_full.sh: cannot mount a small tmpfs (not root?): skipped"
  exit 77
fi
case $mode in
  pic-frames) args="pool-2d --steps 20" ;;
  pic-checkpoint) args="pool-2d --steps 6 --checkpoint-every 2" ;;
  pic-3d-first-frame) args="pool-3d --steps 3" ;;
  sph-checkpoint) args="sph-dam-break-2d --steps 30 --checkpoint-every 5" ;;
  *) echo "disk_full.sh: unknown mode $mode"; exit 3 ;;
esac
# shellcheck disable=SC2086
out=$("$liquid" run $args --out "$dir/o" 2>&1)
status=$?
printf '%s\n' "$out" | grep -v '%  t = '
fail=0
[ "$status" -eq 1 ] || { echo "disk_full.sh: exit status $status, expected 1"; fail=1; }
printf '%s' "$out" | grep -q "No space left on device" || { echo "disk_full.sh: no 'No space left on device'"; fail=1; }
if printf '%s' "$out" | grep -q "HDF5-DIAG"; then echo "disk_full.sh: HDF5 diagnostics printed"; fail=1; fi
left=$(find "$dir" -name '*.tmp' -o -name '*.part')
[ -z "$left" ] || { echo "disk_full.sh: temporaries left: $left"; fail=1; }
exit $fail
