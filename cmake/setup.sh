#!/usr/bin/env bash
# Installs everything lanes needs on a Debian 12 machine, as root:
#   bash cmake/setup.sh
# Safe to run again: when every package is already installed it only checks
# (dpkg-query, well under a second) and touches neither apt's lists nor the
# network, so the main and test commands can always start with it.
set -euo pipefail

# Build tools, the second compiler CI checks with, qemu-user for the dispatch
# tests on emulated CPUs, and the libraries later steps link (Embree as the
# reference tracer and its tutorial path tracer, embree-tools, as a real
# client to race; OpenImageIO for images, Assimp for meshes, cJSON).
packages=(
    build-essential cmake clang-14 clang binutils pkg-config git ca-certificates
    qemu-user gnuplot-nox embree-tools
    libembree-dev libopenimageio-dev openimageio-tools libassimp-dev libcjson-dev
    libomp-14-dev libclang-rt-14-dev
    python3
)

die() {
    echo "cmake/setup.sh: error: $*" >&2
    exit 1
}

missing=()
for p in "${packages[@]}"; do
    status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
    [[ $status == installed ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
    echo "cmake/setup.sh: all ${#packages[@]} packages already installed"
    exit 0
fi

echo "cmake/setup.sh: installing: ${missing[*]}"
[[ $(id -u) -eq 0 ]] || die "run as root (apt-get install needs it); missing: ${missing[*]}"
command -v apt-get >/dev/null || die "apt-get not found: this script is for Debian 12"

export DEBIAN_FRONTEND=noninteractive
# </dev/null: CI has no terminal, and no package may stop to ask a question.
apt-get update </dev/null ||
    die "apt-get update failed (is the Debian archive reachable?)"
apt-get install -y --no-install-recommends "${missing[@]}" </dev/null ||
    die "apt-get install failed for: ${missing[*]}"

# Confirm, so a package apt skipped silently is caught here rather than as a
# confusing build error later.
still=()
for p in "${missing[@]}"; do
    status=$(dpkg-query -W -f='${db:Status-Status}' "$p" 2>/dev/null || true)
    [[ $status == installed ]] || still+=("$p")
done
((${#still[@]} == 0)) || die "still not installed after apt-get: ${still[*]}"
echo "cmake/setup.sh: done"
