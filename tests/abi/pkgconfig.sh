#!/bin/sh
# Build against an installed libnerf the way users do, through pkg-config.
#
#   pkgconfig.sh BUILD_DIR VERSION CXX_EXAMPLE SANITIZE [WRAPPER...]
#
# The build is installed with --destdir into BUILD_DIR/abi-pkgconfig; then
# a C99 program (-pedantic -Werror) is compiled and linked with the flags
# `pkg-config --cflags --libs nerf` gives, and must print VERSION when run
# against the staged library; the C++17 example CXX_EXAMPLE must compile
# and link the same way.  SANITIZE is meson's b_sanitize: a sanitized
# libnerf needs its runtime in the programs too.  Skipped (77) without
# pkg-config, meson or a C or C++ compiler.
#
# Then, as a user of the installed tree does, with an empty environment
# (no LD_LIBRARY_PATH, no ldconfig): the staged nerf-info and
# `nerf-train --help` must start (their install rpath finds the staged
# library; NERF_EXAMPLES=false skips them for a build without examples),
# and the compile line of docs/tutorial-c.md (NERF_TUTORIAL_DOC), taken
# from the document, must build examples/tutorial.c (NERF_TUTORIAL_SRC)
# into a program that starts with the staged library.
#
# In a cross build tests/abi/meson.build sets CC and CXX to the cross
# compilers and PKG_CONFIG_LIBDIR to the host machine's .pc files, and
# passes as WRAPPER the command that runs host programs (qemu-user); the C
# program is run through it.
set -eu
build=$1 version=$2 cxx_example=$3 sanitize=$4
shift 4
cc=${CC:-cc}
cxx=${CXX:-c++}
meson=${MESON:-meson}

for tool in pkg-config "$meson" "$cc" "$cxx"; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "$tool not found: skipping"
    exit 77
  fi
done

scratch=$build/abi-pkgconfig
stage=$scratch/stage
rm -rf "$scratch"
mkdir -p "$scratch/pc"

# meson test builds only what the tests it runs depend on, so a fresh
# build may lack targets that install wants; only then let install build
# them (a build while other tests run could relink programs under them).
if ! "$meson" install -C "$build" --destdir "$stage" --no-rebuild \
     >"$scratch/install.log" 2>&1; then
  echo "install --no-rebuild failed; installing with a rebuild"
  if ! "$meson" install -C "$build" --destdir "$stage" \
       >"$scratch/install.log" 2>&1; then
    cat "$scratch/install.log"
    exit 1
  fi
fi

pc=$(find "$stage" -path '*/pkgconfig/nerf.pc' | head -n 1)
if [ -z "$pc" ]; then
  echo "no pkgconfig/nerf.pc under $stage"
  exit 1
fi
# The .pc file names the configured prefix (say /usr/local), where nothing
# was installed: point every absolute path it defines into the stage.
# (PKG_CONFIG_SYSROOT_DIR would also move the system paths of the
# libraries nerf.pc requires, and --define-prefix guesses the prefix from
# the file's depth, which a multiarch libdir defeats.)
sed "s|^\([A-Za-z_][A-Za-z0-9_]*\)=/|\1=$stage/|" "$pc" >"$scratch/pc/nerf.pc"
PKG_CONFIG_PATH=$scratch/pc
export PKG_CONFIG_PATH
cflags=$(pkg-config --cflags nerf)
libs=$(pkg-config --libs nerf)
libdir=$(pkg-config --variable=libdir nerf)
echo "pkg-config --cflags --libs nerf: $cflags $libs"

san=""
if [ "$sanitize" != none ] && [ -n "$sanitize" ]; then
  san="-fsanitize=$sanitize"
fi

cat >"$scratch/version.c" <<'C'
#include <nerf.h>
#include <stdio.h>
int main(void)
{
    puts(nerf_version_string());
    return nerf_version_number() != NERF_VERSION_NUMBER;
}
C
# shellcheck disable=SC2086 # flag lists are meant to split into words
"$cc" -std=c99 -pedantic -Wall -Wextra -Werror $san $cflags \
  "$scratch/version.c" -o "$scratch/version" $libs

# Only the staged copy may be found: not the build's, not an installed one.
printed=$(LD_LIBRARY_PATH=$libdir "$@" "$scratch/version")
if [ "$printed" != "$version" ]; then
  echo "the C program printed '$printed', expected '$version'"
  exit 1
fi
if [ $# -gt 0 ]; then
  # The build machine's ldd cannot read a program of another machine.
  echo "cross build: not checking with ldd where libnerf was loaded from"
elif command -v ldd >/dev/null 2>&1; then
  loaded=$(LD_LIBRARY_PATH=$libdir ldd "$scratch/version" | grep libnerf)
  case $loaded in
    *"$libdir"/*) ;;
    *) echo "libnerf not loaded from the stage: $loaded"; exit 1 ;;
  esac
fi
echo "ok   C99 -pedantic program built with pkg-config prints $printed"

# shellcheck disable=SC2086
"$cxx" -std=c++17 -pedantic -Wall -Wextra -Werror $san $cflags \
  "$cxx_example" -o "$scratch/nerf_orbit" $libs
echo "ok   C++17 example $(basename "$cxx_example") built with pkg-config"

if [ $# -gt 0 ]; then
  echo "cross build: not running the installed programs or the tutorial"
  exit 0
fi

# The installed programs, started as from a shell with nothing set up.
if [ "${NERF_EXAMPLES:-true}" = true ]; then
  for prog in nerf-info nerf-train; do
    path=$(find "$stage" -type f -name "$prog" | head -n 1)
    if [ -z "$path" ]; then
      echo "$prog was not installed under $stage"
      exit 1
    fi
    set -- "$path"
    [ "$prog" = nerf-train ] && set -- "$path" --help
    if ! env -i "$@" >"$scratch/$prog.out" 2>&1; then
      echo "the installed $* failed to run:"
      cat "$scratch/$prog.out"
      exit 1
    fi
  done
  if ! grep -q "$version" "$scratch/nerf-info.out"; then
    echo "the installed nerf-info did not print version $version:"
    cat "$scratch/nerf-info.out"
    exit 1
  fi
  echo "ok   installed nerf-info and nerf-train --help run with an empty" \
       "environment"
else
  echo "examples disabled: not running installed programs"
fi

# docs/tutorial-c.md's command, as written there (continuation lines
# joined), with this build's compiler and sanitizer.
doc=${NERF_TUTORIAL_DOC:-}
src=${NERF_TUTORIAL_SRC:-}
if [ -z "$doc" ] || [ -z "$src" ]; then
  echo "NERF_TUTORIAL_DOC or NERF_TUTORIAL_SRC not set: not building the" \
       "tutorial"
  exit 1
fi
line=$(awk '
  /^```/ { inblock = !inblock; next }
  inblock && !found && /^cc .*tutorial\.c/ { found = 1 }
  found && inblock {
    cont = sub(/\\$/, "")
    printf "%s ", $0
    if (!cont) exit
  }' "$doc")
case $line in
  "cc "*) ;;
  *) echo "no 'cc ... tutorial.c' command in $doc"; exit 1 ;;
esac
echo "tutorial-c.md: $line"
mkdir -p "$scratch/tutorial"
cp "$src" "$scratch/tutorial/tutorial.c"
line="$cc $san ${line#cc }"
(cd "$scratch/tutorial" && eval "$line")
# Without arguments it prints its usage and exits 2, once the dynamic
# linker has found libnerf (a training run is the 'tutorial' test's job);
# a missing library stops it before main with status 127.
status=0
(cd "$scratch/tutorial" && env -i ./tutorial >run.log 2>&1) || status=$?
if [ "$status" -ne 2 ] || ! grep -q '^usage: tutorial' \
     "$scratch/tutorial/run.log"; then
  echo "the tutorial built with the documented command did not start" \
       "(exit $status):"
  cat "$scratch/tutorial/run.log"
  exit 1
fi
if command -v ldd >/dev/null 2>&1; then
  loaded=$(env -i ldd "$scratch/tutorial/tutorial" | grep libnerf)
  case $loaded in
    *"$libdir"/*) ;;
    *) echo "the tutorial's libnerf is not the staged one: $loaded"; exit 1 ;;
  esac
fi
echo "ok   docs/tutorial-c.md's command builds a tutorial that starts with" \
     "an empty environment"
