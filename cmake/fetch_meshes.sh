#!/usr/bin/env bash
# Fetches the real meshes the built-in scenes use (Stanford bunny, Chinese
# dragon, armadillo, elephant) from Debian's libcgal-demo package, checks
# their SHA-256 sums and caches them:
#   cmake/fetch_meshes.sh [DIR]
# DIR defaults to $LANES_MESH_DIR, else <repo>/out/meshes (where the library
# looks by default). Safe to run again: when every mesh is present with the
# right sum it only checks them and touches neither apt nor the network.
#
# Needs apt-get (with package lists, i.e. after `apt-get update`), dpkg-deb
# and tar; not root. The package is unpacked with `dpkg -x` into a scratch
# directory, so dpkg's path-exclude rules (which Docker images use to drop
# /usr/share/doc) cannot hide the data. LANES_CGAL_DEB=/path/to/the.deb
# skips the download.
#
# Exit status: 0 meshes ready; 77 the package could not be downloaded (no
# network or no package lists: a test fixture treats this as "skipped");
# 1 anything else (a checksum mismatch, a missing tool).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
dest=${1:-${LANES_MESH_DIR:-$here/out/meshes}}

# Sums of the files in libcgal-demo 5.5.1-2 (Debian 12), data.tar.gz:
# data/meshes/. Triangles: bunny00 75,408; ChineseDragon-10kv 19,994;
# armadillo 52,000; elephant 5,558.
declare -A sums=(
    [bunny00.off]=ab651cb04955c161efaeb079035a1e5e1f0e0d1f816a2df67beaea68f393ff2b
    [ChineseDragon-10kv.off]=f633bdfaac7a0f99e0fab668c34862f0c26f341cfdb4665bab282d79b788db02
    [armadillo.off]=6f7f3ca1abc506569466b72f2f59d49493a284e7376d7a7e23c08115ec8cec4e
    [elephant.off]=be4e1ea68f5f840a3d2ada69d828222e76a57d9e25b21e19a9deacd3f2328e02
)
names=(bunny00.off ChineseDragon-10kv.off armadillo.off elephant.off)

say() { echo "fetch_meshes.sh: $*"; }
die() {
    echo "fetch_meshes.sh: error: $*" >&2
    exit 1
}

sum_ok() { # file expected
    [[ -f $1 ]] && [[ $(sha256sum "$1" | cut -d' ' -f1) == "$2" ]]
}

all_present() {
    local n
    for n in "${names[@]}"; do
        sum_ok "$dest/$n" "${sums[$n]}" || return 1
    done
}

if all_present; then
    say "all ${#names[@]} meshes present in $dest"
    exit 0
fi

for tool in sha256sum tar dpkg-deb; do
    command -v "$tool" >/dev/null || die "$tool not found"
done

work=$(mktemp -d "${TMPDIR:-/tmp}/lanes-meshes.XXXXXX")
trap 'rm -rf "$work"' EXIT

# Where the data tarball comes from: a given .deb, else apt-get download.
deb=${LANES_CGAL_DEB:-}
if [[ -z $deb ]]; then
    command -v apt-get >/dev/null || {
        echo "fetch_meshes.sh: apt-get not found; set LANES_CGAL_DEB to a libcgal-demo .deb" >&2
        exit 77
    }
    say "downloading libcgal-demo (about 24 MB) with apt-get download"
    # </dev/null: never wait for an answer in CI.
    if ! (cd "$work" && apt-get download libcgal-demo </dev/null >"$work/apt.log" 2>&1); then
        cat "$work/apt.log" >&2
        echo "fetch_meshes.sh: apt-get download libcgal-demo failed (no network, or run" \
            "'apt-get update' first; or set LANES_CGAL_DEB to the .deb)" >&2
        exit 77
    fi
    deb=$(ls "$work"/libcgal-demo_*.deb 2>/dev/null | head -n 1)
    [[ -n $deb ]] || die "apt-get download reported success but left no .deb"
fi
[[ -f $deb ]] || die "no such file: $deb"

dpkg-deb -x "$deb" "$work/pkg" || die "cannot unpack $deb"
data=$(find "$work/pkg" -name data.tar.gz -path '*libcgal*' | head -n 1)
[[ -n $data ]] || die "$deb holds no data.tar.gz (not libcgal-demo?)"

members=()
for n in "${names[@]}"; do members+=("data/meshes/$n"); done
tar -xzf "$data" -C "$work" "${members[@]}" || die "cannot extract the meshes from $data"

mkdir -p "$dest"
for n in "${names[@]}"; do
    sum_ok "$work/data/meshes/$n" "${sums[$n]}" ||
        die "$n: SHA-256 mismatch (a different libcgal-demo version?); expected ${sums[$n]}"
    # Copy then rename, so an interrupted run never leaves a partial mesh
    # under the final name.
    cp "$work/data/meshes/$n" "$dest/.$n.tmp"
    mv -f "$dest/.$n.tmp" "$dest/$n"
done
say "installed ${#names[@]} meshes in $dest"
