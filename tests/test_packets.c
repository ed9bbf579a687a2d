/* Packet traversal against single-ray traversal, at every instruction set
 * this CPU runs, on generated scenes: every scheme and option must find the
 * same closest hits (same t bitwise; the same triangle unless another one is
 * hit at exactly the same t) and the same occlusion. */
#include "build/bvh.h"
#include "trace/kernels.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tests/harness.h"

static harness_rng rng = {0x243F6A8885A308D3ull};
static float frand(void)
{
    return (float)(harness_next(&rng) >> 40) * 0x1p-24f;
}

static void add_tri(lanes_scene *s, size_t *cap, const float v[9])
{
    if (s->triangle_count == *cap) {
        *cap = *cap ? *cap * 2 : 256;
        s->verts = realloc(s->verts, *cap * 9 * sizeof(float));
        s->material_of = realloc(s->material_of, *cap * sizeof(uint32_t));
    }
    memcpy(s->verts + 9 * s->triangle_count, v, 9 * sizeof(float));
    s->material_of[s->triangle_count++] = 0;
}

/* A closed sphere of latitude/longitude quads (shared edges and vertices),
 * a ground grid, and random small triangles floating around. */
static void make_scene(lanes_scene *s)
{
    size_t cap = 0;
    memset(s, 0, sizeof *s);
    const int nu = 48, nv = 24;
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            float p[4][3];
            for (int c = 0; c < 4; c++) {
                float u = (float)(i + (c & 1)) / nu * 6.2831853f, v = (float)(j + (c >> 1)) / nv * 3.1415926f;
                p[c][0] = sinf(v) * cosf(u);
                p[c][1] = cosf(v) + 1.2f;
                p[c][2] = sinf(v) * sinf(u);
            }
            float a[9] = {p[0][0], p[0][1], p[0][2], p[1][0], p[1][1], p[1][2], p[3][0], p[3][1], p[3][2]};
            float b[9] = {p[0][0], p[0][1], p[0][2], p[3][0], p[3][1], p[3][2], p[2][0], p[2][1], p[2][2]};
            add_tri(s, &cap, a);
            add_tri(s, &cap, b);
        }
    for (int i = 0; i < 20; i++)
        for (int j = 0; j < 20; j++) {
            float x0 = -4.0f + 0.4f * (float)i, z0 = -4.0f + 0.4f * (float)j, x1 = x0 + 0.4f, z1 = z0 + 0.4f;
            float a[9] = {x0, 0, z0, x1, 0, z0, x1, 0, z1};
            float b[9] = {x0, 0, z0, x1, 0, z1, x0, 0, z1};
            add_tri(s, &cap, a);
            add_tri(s, &cap, b);
        }
    for (int i = 0; i < 1500; i++) {
        float c[3] = {frand() * 8 - 4, frand() * 4, frand() * 8 - 4}, v[9];
        for (int k = 0; k < 9; k++) v[k] = c[k % 3] + (frand() - 0.5f) * 0.5f;
        add_tri(s, &cap, v);
    }
}

typedef struct {
    const char *name;
    lanes_ray rays[LANES_PACKET_MAX_RAYS];
    size_t n;
} packet_case;

static void set_ray(lanes_ray *r, float ox, float oy, float oz, float dx, float dy, float dz, float tfar)
{
    *r = (lanes_ray){{ox, oy, oz}, {dx, dy, dz}, {0, 0, 0}, 0.0f, tfar};
}

static void make_cases(packet_case *c, int *count)
{
    int k = 0;
    /* primary: a 32x32 camera packet */
    c[k].name = "primary";
    c[k].n = 0;
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++)
            set_ray(&c[k].rays[c[k].n++], 0.0f, 1.5f, -6.0f, ((float)x - 15.5f) / 40.0f,
                    ((float)y - 15.5f) / 40.0f - 0.1f, 1.0f, INFINITY);
    k++;
    /* primary, wide angle, odd count (partial last group) */
    c[k].name = "primary-wide-997";
    c[k].n = 0;
    for (int i = 0; i < 997; i++)
        set_ray(&c[k].rays[c[k].n++], 0.0f, 2.0f, -7.0f, frand() * 2 - 1, frand() * 2 - 1.2f, 1.0f, INFINITY);
    k++;
    /* shadow: from a light to points on the ground and sphere, finite tfar */
    c[k].name = "shadow";
    c[k].n = 0;
    for (int i = 0; i < 600; i++) {
        float px = frand() * 8 - 4, pz = frand() * 8 - 4, py = 0.001f;
        float dx = px - 1.0f, dy = py - 6.0f, dz = pz - 0.5f;
        set_ray(&c[k].rays[c[k].n++], 1.0f, 6.0f, 0.5f, dx, dy, dz, 0.999f);
    }
    k++;
    /* specular-like: scattered origins on the sphere, reflected directions */
    c[k].name = "specular";
    c[k].n = 0;
    for (int i = 0; i < 1000; i++) {
        float u = frand() * 6.2831853f, v = frand() * 3.1415926f;
        float nx = sinf(v) * cosf(u), ny = cosf(v), nz = sinf(v) * sinf(u);
        set_ray(&c[k].rays[c[k].n++], nx * 1.001f, ny * 1.001f + 1.2f, nz * 1.001f,
                nx + frand() - 0.5f, ny + frand() - 0.5f, nz + frand() - 0.5f, INFINITY);
    }
    k++;
    /* mixed signs, axis-parallel rays with +-0, NaN and inactive rays mixed in */
    c[k].name = "awkward";
    c[k].n = 0;
    for (int i = 0; i < 301; i++) {
        float ox = frand() * 8 - 4, oz = frand() * 8 - 4;
        switch (i % 6) {
        case 0: set_ray(&c[k].rays[c[k].n++], ox, 5.0f, oz, 0.0f, -1.0f, -0.0f, INFINITY); break;
        case 1: set_ray(&c[k].rays[c[k].n++], ox, 0.5f, oz, frand() - 0.5f, frand() - 0.5f, frand() - 0.5f, INFINITY); break;
        case 2: set_ray(&c[k].rays[c[k].n++], ox, NAN, oz, 0.0f, -1.0f, 0.0f, INFINITY); break;
        case 3: set_ray(&c[k].rays[c[k].n++], ox, 5.0f, oz, 0.0f, -1.0f, 0.0f, -1.0f); break;
        case 4: set_ray(&c[k].rays[c[k].n++], -6.0f, 0.0f, oz, 1.0f, 0.0f, 0.0f, INFINITY); break;
        default: set_ray(&c[k].rays[c[k].n++], ox, 3.0f, oz, -0.0f, -1.0f, 0.0f, 2.5f); break;
        }
    }
    k++;
    /* tiny packets */
    c[k].name = "one-ray";
    c[k].n = 1;
    set_ray(&c[k].rays[0], 0.0f, 1.2f, -6.0f, 0.0f, 0.0f, 1.0f, INFINITY);
    k++;
    *count = k;
}

/* t of the ray against one triangle by the single-ray kernel, or NaN. */
static float t_against(const lanes_kernels *k, lanes_tri_algo algo, const lanes_bvh2 *b,
                       const lanes_ray *r, uint32_t prim)
{
    for (size_t j = 0; j < b->prim_count; j++) {
        if (b->prim_index[j] != prim) continue;
        lanes_triangles view = lanes_triangles_view(&b->tris, j, 1);
        float t, u, v;
        return k->tri_wide_closest[algo](r, &view, 1, &t, &u, &v, NULL) == 0 ? t : NAN;
    }
    return NAN;
}

int main(void)
{
    lanes_scene scene;
    make_scene(&scene);
    lanes_bvh_build_options bo;
    lanes_bvh_default_options(&bo);
    lanes_bvh2 bvh;
    lanes_error err;
    if (lanes_bvh2_build(&scene, &bo, &bvh, &err) != LANES_OK) {
        printf("FAIL: BVH build: %s\n", err.message);
        return 1;
    }
    static packet_case cases[8];
    int ncases;
    make_cases(cases, &ncases);

    lanes_rays pk;
    if (!lanes_rays_alloc(&pk, LANES_PACKET_MAX_RAYS)) return 1;
    static uint32_t prim[LANES_PACKET_MAX_RAYS + 16];
    static float u[LANES_PACKET_MAX_RAYS + 16], v[LANES_PACKET_MAX_RAYS + 16];
    static uint8_t occ[LANES_PACKET_MAX_RAYS + 16], ref_occ[LANES_PACKET_MAX_RAYS];
    static lanes_hit ref_hit[LANES_PACKET_MAX_RAYS];
    for (int isa = 0; isa < LANES_ISA_COUNT; isa++) {
        const lanes_kernels *k = lanes_kernels_for((lanes_isa)isa);
        if (!k || !lanes_isa_supported((lanes_isa)isa)) {
            printf("SKIP %s: not compiled in or not runnable on this CPU\n", lanes_isa_name((lanes_isa)isa));
            harness_skip();
            continue;
        }
        /* default and robust modes: their rays carry exact reciprocals, as
         * the single-ray reference's do (fast mode's estimate differs
         * between lanes_ray_prepare_rcp and the set's rays_prepare) */
        for (int algo = 0; algo < LANES_TRI_ALGO_COUNT; algo++)
            for (int c = 0; c < ncases; c++) {
                const lanes_accuracy acc = algo == LANES_TRI_WATERTIGHT ? LANES_ACCURACY_ROBUST
                                                                        : LANES_ACCURACY_DEFAULT;
                packet_case *pc = &cases[c];
                lanes_ray prepared[LANES_PACKET_MAX_RAYS];
                for (size_t i = 0; i < pc->n; i++) {
                    prepared[i] = pc->rays[i];
                    lanes_ray_prepare(&prepared[i]);
                }
                /* The reference is the same set's single-ray traversal: the
                 * same arithmetic per ray and triangle, so t must match bitwise. */
                k->trace_bvh2(&bvh, acc, prepared, pc->n, ref_hit, NULL);
                k->occluded_bvh2(&bvh, acc, prepared, pc->n, ref_occ, NULL);
                for (int variant = 0; variant < 16; variant++) {
                    lanes_packet_options po;
                    memset(&po, 0, sizeof po);
                    po.scheme = (variant & 1) ? LANES_PACKET_RANGED : LANES_PACKET_PARTITION;
                    bool use_frustum = variant & 2;
                    po.corner_test = variant & 4;
                    po.leaf_frustum = variant & 8;
                    po.accuracy = acc;
                    for (int occlusion = 0; occlusion < 2; occlusion++) {
                        po.occlusion = occlusion;
                        pk.count = pc->n;
                        for (size_t i = 0; i < pc->n; i++) {
                            const lanes_ray *r = &pc->rays[i];
                            pk.ox[i] = r->o[0], pk.oy[i] = r->o[1], pk.oz[i] = r->o[2];
                            pk.dx[i] = r->d[0], pk.dy[i] = r->d[1], pk.dz[i] = r->d[2];
                            pk.tnear[i] = r->tnear, pk.tfar[i] = r->tfar;
                            prim[i] = LANES_NO_HIT;
                            occ[i] = 0;
                        }
                        k->rays_prepare(&pk, LANES_RCP_EXACT);
                        lanes_frustum f;
                        if (use_frustum) {
                            k->frustum_build(&pk, NULL, pc->n, &f);
                            po.frustum = &f;
                        } else {
                            po.frustum = NULL;
                        }
                        lanes_packet_stats st;
                        memset(&st, 0, sizeof st);
                        k->trace_packet(&bvh, &po, &pk, prim, u, v, occ, (variant & 2) ? &st : NULL);
                        for (size_t i = 0; i < pc->n; i++) {
                            if (occlusion) {
                                CHECK(occ[i] == ref_occ[i], "%s %s algo %d variant %d occlusion: ray %zu got %d want %d",
                                      k->name, pc->name, algo, variant, i, occ[i], ref_occ[i]);
                                continue;
                            }
                            const lanes_hit *h = &ref_hit[i];
                            if (h->prim == LANES_NO_HIT) {
                                CHECK(prim[i] == LANES_NO_HIT, "%s %s algo %d variant %d: ray %zu hit %u, reference misses",
                                      k->name, pc->name, algo, variant, i, prim[i]);
                                continue;
                            }
                            bool same_t = pk.tfar[i] == h->t;
                            CHECK(prim[i] != LANES_NO_HIT && same_t,
                                  "%s %s algo %d variant %d: ray %zu got prim %u t %.9g, reference %u t %.9g",
                                  k->name, pc->name, algo, variant, i, prim[i], (double)pk.tfar[i], h->prim,
                                  (double)h->t);
                            if (prim[i] != h->prim && prim[i] != LANES_NO_HIT && same_t) {
                                /* a tie: the other triangle must be hit at the very same t */
                                float t2 = t_against(k, (lanes_tri_algo)algo, &bvh, &prepared[i], prim[i]);
                                CHECK(t2 == h->t, "%s %s: ray %zu tie claimed with prim %u but its t is %.9g",
                                      k->name, pc->name, i, prim[i], (double)t2);
                            }
                        }
                        if (variant & 2) {
                            CHECK(st.box_ops.active_lanes <= st.box_ops.lane_slots &&
                                      st.tri_ops.active_lanes <= st.tri_ops.lane_slots &&
                                      st.box_ops.lane_slots == st.box_ops.vector_ops * (uint64_t)k->lanes,
                                  "%s: lane counts inconsistent", k->name);
                        }
                    }
                }
            }
        printf("%s: packet traversal checked (%d cases x 2 algorithms x 16 option sets x 2 queries)\n",
               k->name, ncases);
    }
    lanes_rays_free(&pk);
    lanes_bvh2_free(&bvh);
    free(scene.verts);
    free(scene.material_of);
    return harness_summary("test_packets");
}
