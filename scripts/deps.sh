# shellcheck shell=bash
#
# Shared set-up for scripts/test.sh and scripts/demo.sh.  Source it, do not
# run it.  It holds the one list of Debian packages libnerf needs and the
# meson options of the release build, so the two scripts cannot drift apart.

# Everything needed to build, test and run the examples, as Debian packages.
# README.md lists the same packages for people who install them by hand.
# libjpeg-dev is libjpeg-turbo's (libjpeg62-turbo-dev), for JPEG photos.
# libsdl2-dev builds examples/viewer; xvfb and xauth let its test open a
# window without a display.  libdnnl-dev (oneDNN) is optional for the
# library, which builds without it, but listed so that the tests cover the
# bf16 products (meson option bf16).  abigail-tools (abidw, abidiff) lets the
# abi suite compare the ABI with tests/abi/libnerf.abi; without it that test
# is skipped.  clang builds the library a second time (a C library must
# build with both compilers) and, with libclang-rt-dev's libFuzzer, the fuzz
# targets.  python3-meshio is the independent reader the mesh export's
# tests load PLY and OBJ files with (skipped with a message without it).
NERF_DEB_PACKAGES=(gcc g++ libopenblas-dev libpng-dev libjpeg-dev zlib1g-dev
                   libcjson-dev meson ninja-build pkg-config python3-numpy
                   libsdl2-dev xvfb xauth libdnnl-dev abigail-tools
                   clang libclang-rt-dev python3-meshio)

# Optional packages: the test command installs them when it can (as root,
# from the configured apt sources) and carries on without them otherwise;
# the demo does not need them.  colmap (COLMAP, photos to poses) serves
# scripts/colmap-train.sh; its test is skipped without it.  FFmpeg's
# libraries (meson option video) let nerf-render --video write MP4 files,
# and the ffmpeg package's ffprobe and ffmpeg let the test check them;
# without the libraries that test is skipped.  Open MPI (meson option mpi)
# builds nerf-train-mpi and nerf-render-mpi and runs their two-rank test;
# without it that test is skipped.
NERF_DEB_OPTIONAL=(colmap
                   libavcodec-dev libavformat-dev libavutil-dev
                   libswscale-dev ffmpeg
                   libopenmpi-dev openmpi-bin)

# Options of build/release, shared by both scripts so that running one after
# the other reuses the build instead of reconfiguring it back and forth.
# shellcheck disable=SC2034 # used by the scripts that source this file
NERF_RELEASE_OPTIONS=(--werror -Dbuildtype=release)

# Print the packages of NERF_DEB_PACKAGES that dpkg does not report as
# installed, separated by spaces (nothing when all are present).
nerf_missing_packages() {
  local pkg status missing=""
  for pkg in "${NERF_DEB_PACKAGES[@]}"; do
    status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null) || status=""
    case "$status" in
      *" ok installed") ;;
      *) missing="$missing $pkg" ;;
    esac
  done
  printf '%s' "${missing# }"
}

# Make sure the packages are installed.  As root, install what is missing
# with apt-get; otherwise print the command to run and return 1.  On a system
# without dpkg, warn and carry on: meson will name anything it cannot find.
nerf_ensure_packages() {
  if ! command -v dpkg-query >/dev/null 2>&1; then
    echo "deps: dpkg-query not found; not a Debian system, so not checking" \
         "packages (libnerf needs the equivalents of:" \
         "${NERF_DEB_PACKAGES[*]})" >&2
    return 0
  fi
  local missing
  missing=$(nerf_missing_packages)
  if [ -z "$missing" ]; then
    return 0
  fi
  if [ "$(id -u)" -ne 0 ]; then
    echo "deps: missing Debian packages: $missing" >&2
    echo "deps: install them with:" >&2
    echo "sudo apt-get install -y $missing"
    return 1
  fi
  echo "deps: installing missing Debian packages: $missing" >&2
  # stdin is closed so that nothing can wait for an answer (CI has none).
  # shellcheck disable=SC2086 # the list is meant to split into words
  if ! apt-get update </dev/null ||
     ! DEBIAN_FRONTEND=noninteractive apt-get install -y $missing </dev/null
  then
    echo "deps: apt-get failed; install these packages and retry: $missing" >&2
    return 1
  fi
  missing=$(nerf_missing_packages)
  if [ -n "$missing" ]; then
    echo "deps: still missing after apt-get: $missing" >&2
    return 1
  fi
  return 0
}

# Install the packages of NERF_DEB_OPTIONAL that are missing, when running
# as root on Debian; never fails: what cannot be installed is named and its
# tests skip.
nerf_offer_optional_packages() {
  command -v dpkg-query >/dev/null 2>&1 || return 0
  local pkg status missing=""
  for pkg in "${NERF_DEB_OPTIONAL[@]}"; do
    status=$(dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null) || status=""
    case "$status" in
      *" ok installed") ;;
      *) missing="$missing $pkg" ;;
    esac
  done
  missing=${missing# }
  [ -n "$missing" ] || return 0
  if [ "$(id -u)" -ne 0 ]; then
    echo "deps: optional packages not installed: $missing (their tests" \
         "will be skipped; sudo apt-get install -y $missing)" >&2
    return 0
  fi
  echo "deps: installing optional Debian packages: $missing" >&2
  # shellcheck disable=SC2086 # the list is meant to split into words
  if ! DEBIAN_FRONTEND=noninteractive apt-get install -y $missing \
       </dev/null; then
    echo "deps: could not install $missing; their tests will be skipped" >&2
  fi
  return 0
}

# nerf_configure DIR OPTION...: configure a meson build directory, or
# reconfigure it with these options when it was configured before.
nerf_configure() {
  local dir=$1
  shift
  if [ -f "$dir/meson-private/coredata.dat" ]; then
    meson setup --reconfigure "$dir" "$@"
  else
    meson setup "$dir" "$@"
  fi
}
