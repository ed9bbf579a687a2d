/* The rays `lanes compare` and `lanes study` trace (ray_sets.h).
 *
 * Compiled for the x86-64 baseline. */
#include "bench/ray_sets.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "build/camera.h"

static uint64_t splitmix(uint64_t *s)
{
    uint64_t z = (*s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

static float rnd01(uint64_t *s) { return (float)(splitmix(s) >> 40) * 0x1p-24f; }

static lanes_ray make_ray(vec3 o, vec3 d, float tnear, float tfar)
{
    lanes_ray r = {{o.x, o.y, o.z}, {d.x, d.y, d.z}, {0, 0, 0}, tnear, tfar};
    lanes_ray_prepare(&r);
    return r;
}

/* Bits 0, 2, 4 of m (the x of a Morton index within an 8x8 tile). */
static int morton_x(int m) { return (m & 1) | ((m >> 1) & 2) | ((m >> 2) & 4); }

/* The pixel of the i-th ray within a block of the order's size. */
static void block_pixel(ray_order order, int i, int *x, int *y)
{
    if (order == RAY_ORDER_MORTON8) {
        *x = morton_x(i);
        *y = morton_x(i >> 1);
    } else { /* 4x4 tiles, row by row, in a 32x32 quadrant */
        int tile = i >> 4, in = i & 15;
        *x = 4 * (tile & 7) + (in & 3);
        *y = 4 * (tile >> 3) + (in >> 2);
    }
}

lanes_ray *ray_set_camera(const lanes_scene *s, int w, int h, ray_order order, size_t *count)
{
    lanes_view view = lanes_view_make(&s->camera, w, h);
    lanes_ray *rays = malloc((size_t)w * (size_t)h * sizeof *rays);
    if (!rays) return NULL;
    const int side = order == RAY_ORDER_MORTON8 ? 8 : 32;
    size_t n = 0;
    for (int by = 0; by < h; by += side)
        for (int bx = 0; bx < w; bx += side)
            for (int i = 0; i < side * side; i++) {
                int dx, dy;
                block_pixel(order, i, &dx, &dy);
                int x = bx + dx, y = by + dy;
                if (x >= w || y >= h) continue;
                vec3 d = v3_normalize(lanes_view_dir(&view, (float)x + 0.5f, (float)y + 0.5f));
                rays[n++] = make_ray(view.eye, d, 0.0f, INFINITY);
            }
    *count = n;
    return rays;
}

surface_point *ray_set_surface_points(const lanes_scene *s, const lanes_ray *rays, const lanes_hit *hits,
                                      size_t n, size_t *count)
{
    float eps = lanes_scene_epsilon(s);
    surface_point *pts = malloc((n ? n : 1) * sizeof *pts);
    if (!pts) return NULL;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        if (hits[i].prim == LANES_NO_HIT) continue;
        const float *v = s->verts + (size_t)hits[i].prim * 9;
        vec3 v0 = v3_load(v), e1 = v3_sub(v3_load(v + 3), v0), e2 = v3_sub(v3_load(v + 6), v0);
        vec3 p = v3_add(v0, v3_add(v3_scale(e1, hits[i].u), v3_scale(e2, hits[i].v)));
        vec3 nrm = v3_unit_normal(e1, e2);
        if (v3_dot(nrm, v3_load(rays[i].d)) > 0.0f) nrm = v3_scale(nrm, -1.0f);
        pts[m++] = (surface_point){v3_add(p, v3_scale(nrm, eps)), nrm, (uint32_t)i};
    }
    *count = m;
    return pts;
}

/* Towards the first point light, or a point above the scene (along the
 * camera's up) when there is none; only where the light is in front of the
 * surface, as a renderer would cast them. */
lanes_ray *ray_set_shadow(const lanes_scene *s, const surface_point *pts, size_t n, size_t *count)
{
    vec3 light;
    if (s->point_light_count > 0) {
        light = v3_load(s->point_lights[0].position);
    } else {
        float lo[3], hi[3];
        lanes_scene_bounds(s, lo, hi);
        vec3 centre = v3_scale(v3_add(v3_load(lo), v3_load(hi)), 0.5f);
        vec3 diag = v3_sub(v3_load(hi), v3_load(lo));
        light = v3_add(centre, v3_scale(v3_normalize(v3_load(s->camera.up)), sqrtf(v3_dot(diag, diag))));
    }
    lanes_ray *rays = malloc((n ? n : 1) * sizeof *rays);
    if (!rays) return NULL;
    size_t m = 0;
    for (size_t i = 0; i < n; i++) {
        vec3 to = v3_sub(light, pts[i].origin);
        float dist = sqrtf(v3_dot(to, to));
        if (!(dist > 0.0f)) continue;
        vec3 l = v3_scale(to, 1.0f / dist);
        if (v3_dot(l, pts[i].n) <= 0.0f) continue;
        rays[m++] = make_ray(pts[i].origin, l, 0.0f, dist * (1.0f - 1e-4f));
    }
    *count = m;
    return rays;
}

/* Cosine-weighted about the facing normal; the numbers depend only on the
 * pixel, so the rays are the same whatever else changes. */
lanes_ray *ray_set_diffuse(const surface_point *pts, size_t n)
{
    lanes_ray *rays = malloc((n ? n : 1) * sizeof *rays);
    if (!rays) return NULL;
    for (size_t i = 0; i < n; i++) {
        uint64_t seed = 0x5eed0000ull + pts[i].pixel;
        float r1 = rnd01(&seed), r2 = rnd01(&seed);
        vec3 nz = pts[i].n;
        vec3 a = fabsf(nz.x) > 0.9f ? v3(0, 1, 0) : v3(1, 0, 0);
        vec3 nx = v3_normalize(v3_cross(a, nz)), ny = v3_cross(nz, nx);
        float phi = 6.28318530717958647692f * r1, r = sqrtf(r2);
        float lx = r * cosf(phi), ly = r * sinf(phi), lz = sqrtf(fmaxf(0.0f, 1.0f - r2));
        vec3 d = v3_normalize(v3_add(v3_add(v3_scale(nx, lx), v3_scale(ny, ly)), v3_scale(nz, lz)));
        rays[i] = make_ray(pts[i].origin, d, 0.0f, INFINITY);
    }
    return rays;
}

lanes_ray *ray_set_shuffled(const lanes_ray *rays, size_t n)
{
    lanes_ray *out = malloc((n ? n : 1) * sizeof *out);
    if (!out) return NULL;
    memcpy(out, rays, n * sizeof *out);
    uint64_t seed = 0xd1ce;
    for (size_t i = n; i > 1; i--) {
        size_t j = (size_t)(splitmix(&seed) % i);
        lanes_ray t = out[i - 1];
        out[i - 1] = out[j];
        out[j] = t;
    }
    return out;
}
