#!/bin/bash
# lanes paths against a real client of Embree: its tutorial path tracer
# (Debian's embree-tools, /usr/bin/pathtracer: one path at a time with
# rtcIntersect1/rtcOccluded1 and scalar C++ shading, the baseline of Afra et
# al. 2016) on the same mesh, camera, image size, samples per pixel, path
# length, point light, black background and a diffuse material of albedo
# 0.8. Both run as whole processes (load, build, render, write), one
# thread, alternately, --runs times; the table gives each one's median
# samples per second and its ratio to Embree's, with lanes' own render time
# beside it.
#
# usage: bench/embree_pathtracer_client.sh [--lanes PATH] [--mesh OFF] [--size N] [--spp N]
#        [--depth L] [--isa NAME] [--runs N] [--out DIR]
# The mesh is an OFF file (default: the CGAL dragon, cmake/fetch_meshes.sh).
# --isa names a set both know: sse4 (Embree sse4.2), avx, avx2, avx512.
set -euo pipefail

here=$(cd "$(dirname "$0")/.." && pwd)
lanes=$here/out/lanes
mesh=$here/out/meshes/ChineseDragon-10kv.off
size=256
spp=64
depth=8
isa=avx2
runs=5
out=$here/out/paths/embree_client
while [ $# -gt 0 ]; do
    case $1 in
    --lanes) lanes=$2; shift 2 ;;
    --mesh) mesh=$2; shift 2 ;;
    --size) size=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    --depth) depth=$2; shift 2 ;;
    --isa) isa=$2; shift 2 ;;
    --runs) runs=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    *) echo "embree_pathtracer_client.sh: unknown option '$1'" >&2; exit 2 ;;
    esac
done
command -v pathtracer > /dev/null || { echo "embree_pathtracer_client.sh: no pathtracer: apt-get install embree-tools" >&2; exit 2; }
[ -x "$lanes" ] || { echo "embree_pathtracer_client.sh: no lanes binary at $lanes" >&2; exit 2; }
[ -f "$mesh" ] || { echo "embree_pathtracer_client.sh: no mesh $mesh (run cmake/fetch_meshes.sh)" >&2; exit 2; }
case $isa in
sse4) embree_isa=sse4.2 ;;
avx | avx2 | avx512) embree_isa=$isa ;;
*) echo "embree_pathtracer_client.sh: --isa $isa: Embree has no such set (sse4, avx, avx2, avx512)" >&2; exit 2 ;;
esac
mkdir -p "$out"

# OFF to OBJ (polygons as fans), and a camera and a light from the bounds:
# the eye in front of and a little above the centre, the light above it.
awk -v obj="$out/mesh.obj" -v view="$out/view.txt" '
    function word() { while (k > n) { if ((getline line) <= 0) return ""; sub(/#.*/, "", line); n = split(line, w); k = 1 } return w[k++] }
    BEGIN {
        k = 1; n = 0
        head = word(); if (head != "OFF") { print "not an OFF file" > "/dev/stderr"; exit 2 }
        nv = word() + 0; nf = word() + 0; word()
        print "mtllib mesh.mtl" > obj
        for (i = 0; i < nv; i++) {
            x = word() + 0; y = word() + 0; z = word() + 0
            print "v", x, y, z > obj
            if (i == 0 || x < lo[0]) lo[0] = x; if (i == 0 || x > hi[0]) hi[0] = x
            if (i == 0 || y < lo[1]) lo[1] = y; if (i == 0 || y > hi[1]) hi[1] = y
            if (i == 0 || z < lo[2]) lo[2] = z; if (i == 0 || z > hi[2]) hi[2] = z
        }
        print "usemtl white" > obj
        for (i = 0; i < nf; i++) {
            c = word() + 0
            for (j = 0; j < c; j++) f[j] = word() + 1
            for (j = 1; j + 1 < c; j++) print "f", f[0], f[j], f[j + 1] > obj
        }
        r = 0
        for (a = 0; a < 3; a++) { m[a] = (lo[a] + hi[a]) / 2; r += (hi[a] - lo[a]) ^ 2 }
        r = sqrt(r) / 2
        printf "%.6g %.6g %.6g  %.6g %.6g %.6g  %.6g %.6g %.6g  %.6g\n", m[0], m[1] + 0.6 * r, m[2] + 2.6 * r,
               m[0], m[1], m[2], m[0] + r, m[1] + 2 * r, m[2] + r, 4 * r * r > view
    }' < "$mesh"
printf 'newmtl white\nKd 0.8 0.8 0.8\nKs 0 0 0\n' > "$out/mesh.mtl"
read -r ex ey ez tx ty tz lx ly lz li < "$out/view.txt"
# A black background: Embree's tutorial samples an ambient light with
# shadow rays, where lanes' uniform background is only what misses see.
background=0
cat > "$out/scene.json" <<EOF
{"materials": {"white": {"type": "diffuse", "color": 0.8}},
 "objects": [{"mesh": "mesh.obj", "material": "white"}],
 "lights": [{"type": "point", "position": [$lx, $ly, $lz], "intensity": $li}],
 "camera": {"eye": [$ex, $ey, $ez], "target": [$tx, $ty, $tz], "up": [0, 1, 0], "fov": 40, "width": $size, "height": $size}}
EOF

now() { date +%s.%N; }
embree_run() {
    pathtracer -i "$out/mesh.obj" -o "$out/embree.tga" --vp "$ex" "$ey" "$ez" --vi "$tx" "$ty" "$tz" --vu 0 1 0 --fov 40 \
        --size "$size" "$size" --spp "$spp" --max-path-length "$depth" --threads 1 --isa "$embree_isa" \
        --pointlight "$lx" "$ly" "$lz" "$li" "$li" "$li" > /dev/null
}
lanes_run() {
    "$lanes" --isa "$isa" paths "$out/scene.json" -o "$out/lanes_$1.exr" --method "$1" --spp "$spp" --depth "$depth" \
        --background $background --threads 1 --json > "$out/lanes_$1.json"
}
methods="single packet stream"
: > "$out/times.txt"
for ((run = 0; run < runs; run++)); do
    t0=$(now); embree_run; t1=$(now)
    echo "embree $t0 $t1 0" >> "$out/times.txt"
    for m in $methods; do
        t0=$(now); lanes_run "$m"; t1=$(now)
        render=$(sed -n 's/.*"seconds": \([0-9.e+-]*\).*/\1/p' "$out/lanes_$m.json")
        echo "$m $t0 $t1 $render" >> "$out/times.txt"
    done
done
samples=$((size * size * spp))
cpu=$(sed -n 's/^model name[^:]*: //p' /proc/cpuinfo | head -1)
echo "mesh $(basename "$mesh"), ${size}x${size}, $spp spp, path length $depth, 1 thread, set $isa (Embree $embree_isa), on $cpu"
echo "medians of $runs runs, alternating; whole processes (load, build, render, write)"
awk -v samples=$samples '
    { k = ++n[$1]; t[$1, k] = $3 - $2; r[$1, k] = $4 }
    function median(a, name, k,   i, j, x, v) {
        for (i = 1; i <= k; i++) v[i] = a[name, i]
        for (i = 2; i <= k; i++) { x = v[i]; for (j = i - 1; j > 0 && v[j] > x; j--) v[j + 1] = v[j]; v[j + 1] = x }
        return k % 2 ? v[(k + 1) / 2] : (v[k / 2] + v[k / 2 + 1]) / 2
    }
    END {
        e = median(t, "embree", n["embree"])
        printf "%-22s %10s %14s %12s %14s\n", "client", "seconds", "samples/s", "vs Embree", "render seconds"
        printf "%-22s %10.3f %14.0f %12s %14s\n", "Embree pathtracer", e, samples / e, "1.00", "-"
        split("single packet stream", ms, " ")
        for (i = 1; i <= 3; i++) {
            m = ms[i]; s = median(t, m, n[m]); rr = median(r, m, n[m])
            printf "%-22s %10.3f %14.0f %12.2f %14.3f\n", "lanes paths " m, s, samples / s, e / s, rr
        }
    }' "$out/times.txt"
