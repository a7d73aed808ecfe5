#!/usr/bin/env bash
# rosdep over package.xml on Debian 12, without the internet:
#   tools/ci/check_rosdep.sh           rosdep check: every key resolves and its
#                                   Debian packages are installed
#   tools/ci/check_rosdep.sh install   rosdep install -y: installs what is missing
# The sources are Debian's own rosdep database and rosdep/debian.yaml, in a
# private cache (tools/ci/rosdep_env.sh). `make check` runs the check, so that package.xml and
# tools/ci/install_deps.sh cannot drift apart.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
mode=${1:-check}
if ! command -v rosdep > /dev/null; then
  echo "check_rosdep: rosdep not installed (apt-get install python3-rosdep2)" >&2
  exit 1
fi
# shellcheck source=tools/ci/rosdep_env.sh
source "$root/tools/ci/rosdep_env.sh"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if ! rosdep_env "$tmp"; then
  echo "check_rosdep: rosdep update failed" >&2
  exit 1
fi
case "$mode" in
  check)
    # rosdep check exits 0 on a key it cannot resolve; its ERROR line counts.
    if ! out=$(rosdep check --from-paths "$root" --ignore-src --rosdistro debian 2>&1) ||
      grep -q '^ERROR' <<< "$out"; then
      echo "$out" >&2
      echo "check_rosdep: rosdep check failed (keys above: add the package to" \
        "tools/ci/install_deps.sh, or the key to rosdep/debian.yaml)" >&2
      exit 1
    fi
    echo "check_rosdep: every key of package.xml resolves and is installed"
    ;;
  install)
    rosdep install -y --from-paths "$root" --ignore-src --rosdistro debian
    ;;
  *)
    echo "usage: check_rosdep.sh [check|install]" >&2
    exit 1
    ;;
esac
