#!/bin/sh
# check-listing.sh DOC LANG SOURCE: the ```LANG blocks of the Markdown file
# DOC, put together in order, must be the file SOURCE (blank lines aside,
# since the page splits the program between them).  It keeps a tutorial's
# listing identical to the program that the build compiles and a test runs.
set -eu
doc=$1 lang=$2 source=$3
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

awk -v lang="$lang" '
  /^```/ {
    if (inside) { inside = 0; next }
    if ($0 == "```" lang) { inside = 1; next }
  }
  inside { print }
' "$doc" | grep -v '^[[:space:]]*$' >"$tmp/doc" || true
grep -v '^[[:space:]]*$' "$source" >"$tmp/source" || true

if ! [ -s "$tmp/doc" ]; then
  echo "$doc has no \`\`\`$lang blocks"
  exit 1
fi
if ! diff -u "$tmp/source" "$tmp/doc" >"$tmp/diff"; then
  echo "the $lang blocks of $doc differ from $source (- source, + page):"
  cat "$tmp/diff"
  exit 1
fi
echo "ok   $doc shows all of $source"
