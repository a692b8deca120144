#!/bin/sh
# Installs the Debian 12 packages the project needs, only those missing. One list for the
# Makefile, CI and the container image.
#   docker/install-deps.sh          build + run + test dependencies
#   docker/install-deps.sh --build  only what `make build` needs (the container image's build
#                                   stage: no browser, no test framework, no optional data)
#   docker/install-deps.sh --print  print the apt-get line for what is missing, install nothing
#   docker/install-deps.sh --list   print the packages of the chosen set, one a line
# --build combines with --print and --list. The Makefile passes DEPS_MODE=build as --build.
set -eu

# What compiling the server, both workers and the web bundle needs (glslang-tools too: the
# CMake config of Debian's glslang-dev checks that glslangValidator exists).
BUILD_PACKAGES="build-essential cmake pkg-config \
libvulkan-dev glslang-dev glslang-tools \
libglm-dev libtinyobjloader-dev libcpp-httplib-dev libssl-dev libbrotli-dev zlib1g-dev \
nlohmann-json3-dev libstb-dev libtinyexr-dev libopenexr-dev libdeflate-dev libnlopt-dev \
nodejs npm"
# Running on this machine (lavapipe) and testing (GoogleTest, the browser tests' Chromium,
# clang-format for the layout check).
RUN_TEST_PACKAGES="mesa-vulkan-drivers libgtest-dev chromium haproxy clang-format"

# Wanted but not required: blender-data ships eight CC0 equirectangular EXR worlds that the
# server offers as environments blender_<name> when present. Tried once per machine.
OPTIONAL="blender-data"
OPTIONAL_STAMP=/var/lib/brdfa-optional-packages-tried

mode=all
print=""
list=""
for arg in "$@"; do
  case "$arg" in
    --build) mode=build ;;
    --print) print=1 ;;
    --list) list=1 ;;
    *) echo "usage: $0 [--build] [--print | --list]" >&2; exit 2 ;;
  esac
done
if [ "$mode" = build ]; then
  PACKAGES="$BUILD_PACKAGES"
  OPTIONAL=""
else
  PACKAGES="$BUILD_PACKAGES $RUN_TEST_PACKAGES"
fi
if [ -n "$list" ]; then
  # shellcheck disable=SC2086
  printf '%s\n' $PACKAGES
  exit 0
fi

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

# The web UI's build and browser tests need node, npm and chromium (web/package.json). A
# NodeSource `nodejs` bundles npm and conflicts with Debian's `npm` package: a working command
# counts as installed, so the script never tries to replace one Node.js with another.
present() {
  case "$1" in
    nodejs) command -v node >/dev/null 2>&1 ;;
    npm) command -v npm >/dev/null 2>&1 ;;
    *) return 1 ;;
  esac
}

try_optional() {
  [ "$(id -u)" = "0" ] && [ -z "$print" ] || return 0
  [ -n "$OPTIONAL" ] || return 0
  [ -e "$OPTIONAL_STAMP" ] && return 0
  for p in $OPTIONAL; do
    installed "$p" && continue
    echo "Installing optional: $p"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "$p" ||
      echo "optional package $p could not be installed; continuing without it" >&2
  done
  touch "$OPTIONAL_STAMP" 2>/dev/null || true
}

missing=""
for p in $PACKAGES; do
  if ! installed "$p" && ! present "$p"; then
    missing="$missing $p"
  fi
done

if [ -z "$missing" ]; then
  try_optional
  exit 0
fi
if [ -n "$print" ] || [ "$(id -u)" != "0" ]; then
  echo "Missing packages. Install them with:" >&2
  echo "  sudo apt-get install -y$missing" >&2
  [ -n "$print" ] && exit 0
  exit 1
fi
echo "Installing:$missing"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
# shellcheck disable=SC2086
apt-get install -y -qq --no-install-recommends $missing
try_optional
