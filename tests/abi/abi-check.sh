#!/bin/sh
# The ABI checked the way distributions check it: libabigail (Debian:
# abigail-tools) compares what this build exports with the baseline
# committed in tests/abi.
#
#   abi-check.sh check|update SRC_DIR BUILD_DIR LIBRARY TYPES_MODULE SANITIZE
#
# Two corpora, each with its baseline:
#   libnerf.abi        LIBRARY (libnerf.so): the exported functions, their
#                      symbol versions and every type their parameters and
#                      return values reach, the public structs included;
#   libnerf-types.abi  TYPES_MODULE (tests/abi/abi_types.c): the enums of
#                      nerf.h, which no function signature mentions.
# Only the public headers' types count: --drop-private-types hides what
# the opaque handles point to, --drop-undefined-syms what the library
# calls (libc, BLAS, oneDNN), which varies with the machine.
#
# check passes when nothing changed, or when only functions or enum values
# were added.  Any other change fails with abidiff's report, a field
# appended under the struct_size rules included: libabigail 2.2's
# suppression for appended fields also hides a field whose type changes
# at the same size, so an append, like any layout change, is confirmed by
# regenerating the baseline (docs/abi-versioning.md).  A baseline of
# another soname fails too: it cannot say what the new soname promises.
# Skipped (77) without abidw/abidiff, on another architecture than the
# baseline's, and for a library without debug information.
#
# update rewrites both baselines from this build (scripts/abi-baseline.sh).
set -eu
mode=$1 src=$2 build=$3 lib=$4 types=$5 sanitize=$6
here=$src/tests/abi
regenerate="regenerate the baseline with scripts/abi-baseline.sh"

skip() {
  echo "skipped: $*"
  exit 77
}

case $mode in
  check|update) ;;
  *) echo "usage: $0 check|update SRC_DIR BUILD_DIR LIBRARY TYPES_MODULE SANITIZE"; exit 2 ;;
esac

for tool in abidw abidiff readelf; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    [ "$mode" = check ] || { echo "$tool not found (Debian: abigail-tools, binutils)"; exit 1; }
    skip "$tool not found; install Debian's abigail-tools to compare the ABI with tests/abi/libnerf.abi"
  fi
done

# The sanitizers change no exported type or symbol (the version script
# hides what they add, and the types module is built without them), so
# sanitized builds are checked too; but a baseline comes from a plain one.
if [ "$mode" = update ] && [ "$sanitize" != none ] && [ -n "$sanitize" ]; then
  echo "refusing to write the baseline from a sanitized build (b_sanitize=$sanitize)"
  exit 1
fi

for f in "$lib" "$types"; do
  if ! readelf -S "$f" | grep -q '\.debug_info'; then
    [ "$mode" = check ] || { echo "$f has no debug information"; exit 1; }
    skip "$f has no debug information (built with -g0?); abidiff needs DWARF"
  fi
done

out=$build/abi-check
rm -rf "$out"
mkdir -p "$out"

# Source locations, paths and DT_NEEDED are left out: they vary with the
# machine and the build directory, not with the ABI.  Hashed type ids
# keep a regenerated baseline's diff down to what changed.
for name in libnerf.abi:"$lib" libnerf-types.abi:"$types"; do
  abidw --headers-dir "$src/include" --headers-dir "$build/include" \
        --drop-private-types --drop-undefined-syms --no-corpus-path \
        --no-comp-dir-path --no-show-locs --no-elf-needed \
        --type-id-style hash --out-file "$out/${name%%:*}" "${name#*:}"
done

# Every enum of nerf.h must be in the types corpus, or its values go
# unchecked.
missing=""
# shellcheck disable=SC2013 # enum names are single words
for enum in $(sed -n 's/^typedef enum \(nerf_[a-z0-9_]*\).*/\1/p' "$src/include/nerf.h"); do
  grep -q "<enum-decl name='$enum'" "$out/libnerf-types.abi" || missing="$missing $enum"
done
if [ -n "$missing" ]; then
  echo "FAIL: enums of nerf.h missing from tests/abi/abi_types.c:$missing"
  exit 1
fi

if [ "$mode" = update ]; then
  cp "$out/libnerf.abi" "$out/libnerf-types.abi" "$here/"
  echo "wrote $here/libnerf.abi and $here/libnerf-types.abi"
  exit 0
fi

# corpus_attr FILE NAME: an attribute of the abi-corpus element.
corpus_attr() {
  sed -n "/<abi-corpus /{s/.* $2='\([^']*\)'.*/\1/p;q;}" "$1"
}

base_arch=$(corpus_attr "$here/libnerf.abi" architecture)
arch=$(corpus_attr "$out/libnerf.abi" architecture)
if [ "$base_arch" != "$arch" ]; then
  skip "the baseline describes $base_arch, this build is $arch"
fi

status=0
base_soname=$(corpus_attr "$here/libnerf.abi" soname)
soname=$(corpus_attr "$out/libnerf.abi" soname)
if [ "$base_soname" != "$soname" ]; then
  echo "FAIL: the soname moved from $base_soname (baseline) to $soname."
  echo "      A new soname may break the ABI, but the baseline must then"
  echo "      describe the new one: $regenerate"
  echo "      in the commit that moves the soname.  Changes since the baseline:"
  status=1
fi

# compare NAME: diff one corpus with its baseline.  Added functions and
# variables are compatible, so --no-added-syms leaves them out of the
# verdict; they are listed afterwards for the log.
compare() {
  name=$1
  rc=0
  abidiff --no-added-syms --ignore-soname "$here/$name" "$out/$name" \
          >"$out/$name.diff" 2>&1 || rc=$?
  if [ $((rc & 3)) -ne 0 ]; then
    cat "$out/$name.diff"
    echo "FAIL: abidiff could not compare $name (status $rc)"
    status=1
  elif [ "$rc" -ne 0 ]; then
    cat "$out/$name.diff"
    echo "FAIL: $name: the ABI changed since the baseline (abidiff status $rc)."
    echo "      Undo the change, unless it is a field appended under the"
    echo "      struct_size rules or a deliberate break (docs/abi-versioning.md):"
    echo "      then $regenerate in the same commit."
    status=1
  else
    echo "ok   $name: nothing removed or changed since the baseline"
    if ! abidiff --ignore-soname "$here/$name" "$out/$name" \
         >"$out/$name.diff" 2>&1; then
      echo "     added since the baseline:"
      sed 's/^/     /' "$out/$name.diff"
    fi
  fi
}

compare libnerf.abi
compare libnerf-types.abi
exit $status
