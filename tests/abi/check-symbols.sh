#!/bin/sh
# The shared library must export exactly the symbols the version script
# lists under "global:", and every one of them must start with nerf_.
set -eu
so=$1
map=$2
exported=$(mktemp)
listed=$(mktemp)
trap 'rm -f "$exported" "$listed"' EXIT

nm -D --defined-only "$so" | awk '$2 ~ /^[TDBRWVi]$/ {print $3}' | sed 's/@.*//' \
  | grep -Ev '^(_init|_fini|_edata|_end|__bss_start)$' | sort -u > "$exported"
sed 's,/\*.*\*/,,' "$map" | tr -d ' \t' | grep -E '^nerf_[A-Za-z0-9_]+;$' \
  | tr -d ';' | sort -u > "$listed"

status=0
if ! diff -u "$listed" "$exported"; then
  echo "exported symbols (+) differ from $map (-)"
  status=1
fi
if grep -v '^nerf_' "$exported"; then
  echo "symbols above are exported without the nerf_ prefix"
  status=1
fi
count=$(wc -l < "$exported")
if [ "$count" -eq 0 ]; then
  echo "no symbols found in $so"
  status=1
fi
[ $status -eq 0 ] && echo "ok   $count exported symbols match the version script"
exit $status
