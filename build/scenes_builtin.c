/* Built-in scenes and objects. Everything here is deterministic: the only
 * randomness is PCG32 with fixed seeds, written out below so no library
 * version can change a scene.
 *
 * Compiled for the x86-64 baseline. */
#define _POSIX_C_SOURCE 200809L /* stat, to tell a missing mesh from a broken one */

#include "build/scenes_builtin.h"

#include "build/mesh_builder.h"
#include "build/mesh_ops.h"

#include "build/memory_limit.h"
#include "build/mesh_import.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#ifndef LANES_DEFAULT_MESH_DIR
#define LANES_DEFAULT_MESH_DIR "out/meshes"
#endif

/* ---- PCG32 (O'Neill), the reference pcg32_random_r ---- */

typedef struct pcg32 {
    uint64_t state, inc;
} pcg32;

static uint32_t pcg32_next(pcg32 *r)
{
    uint64_t old = r->state;
    r->state = old * 6364136223846793005ull + r->inc;
    uint32_t xs = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (xs >> rot) | (xs << ((32u - rot) & 31u));
}

static void pcg32_seed(pcg32 *r, uint64_t seed, uint64_t seq)
{
    r->state = 0;
    r->inc = (seq << 1u) | 1u;
    pcg32_next(r);
    r->state += seed;
    pcg32_next(r);
}

/* Uniform in [0, 1). */
static double rnd(pcg32 *r)
{
    return pcg32_next(r) * (1.0 / 4294967296.0);
}

/* Uniform in [-1, 1]^3 restricted to the unit ball (rejection). */
static void rnd_ball(pcg32 *r, double p[3])
{
    do {
        for (int a = 0; a < 3; a++)
            p[a] = 2.0 * rnd(r) - 1.0;
    } while (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] > 1.0);
}

/* ---- the CGAL meshes ---- */

static const struct {
    const char *name, *file;
    double yaw; /* degrees about +y so the model faces +z */
} cgal_meshes[] = {
    {"bunny", "bunny00.off", 90.0},
    {"dragon", "ChineseDragon-10kv.off", 0.0},
    {"armadillo", "armadillo.off", 180.0},
    {"elephant", "elephant.off", 0.0},
};
#define N_CGAL (sizeof cgal_meshes / sizeof cgal_meshes[0])

const char *lanes_mesh_dir(void)
{
    const char *e = getenv("LANES_MESH_DIR");
    return e && *e ? e : LANES_DEFAULT_MESH_DIR;
}

static bool mesh_path(const char *file, char *out, size_t n)
{
    int k = snprintf(out, n, "%s/%s", lanes_mesh_dir(), file);
    return k > 0 && (size_t)k < n;
}

bool lanes_builtin_meshes_available(void)
{
    for (size_t i = 0; i < N_CGAL; i++) {
        char p[4096];
        struct stat st;
        if (!mesh_path(cgal_meshes[i].file, p, sizeof p) || stat(p, &st) != 0)
            return false;
    }
    return true;
}

static lanes_status load_cgal(size_t which, int subdiv, lanes_mesh *out, lanes_error *err)
{
    lanes_status status;
    char path[4096];
    struct stat st;
    if (!mesh_path(cgal_meshes[which].file, path, sizeof path)) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: mesh directory path too long",
                               cgal_meshes[which].name);
    }
    if (stat(path, &st) != 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: mesh file %s not found: run cmake/fetch_meshes.sh (or set "
                               "LANES_MESH_DIR to where it put the meshes)",
                               cgal_meshes[which].name, path);
    }
    lanes_mesh m;
    if ((status = lanes_mesh_read(path, &m, err)) != LANES_OK) return status;
    for (int i = 0; i < subdiv; i++) {
        lanes_mesh fine;
        status = lanes_mesh_subdivide(&m, &fine, err);
        lanes_mesh_free(&m);
        if (status != LANES_OK) return status;
        m = fine;
    }
    lanes_xform rot, norm, x;
    const double up[3] = {0, 1, 0};
    lanes_xform_rotation(&rot, up, cgal_meshes[which].yaw);
    for (size_t v = 0; v < m.vertex_count; v++)
        lanes_xform_apply(&rot, m.positions + 3 * v, m.positions + 3 * v);
    lanes_mesh_normalizing_xform(&m, &norm);
    x = norm;
    for (size_t v = 0; v < m.vertex_count; v++)
        lanes_xform_apply(&x, m.positions + 3 * v, m.positions + 3 * v);
    *out = m;
    return LANES_OK;
}

static const char *const primitive_names[] = {"sphere", "box", "plane", "cylinder"};

const char *lanes_builtin_object_names(void)
{
    return "sphere, box, plane, cylinder, bunny, dragon, armadillo, elephant";
}

lanes_status lanes_builtin_object(const char *name, int detail, lanes_mesh *out, lanes_error *err)
{
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < N_CGAL; i++) {
        if (strcmp(name, cgal_meshes[i].name) == 0) {
            if (detail > 4) {
                return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: detail %d: at most 4 subdivision steps",
                                       name, detail);
            }
            return load_cgal(i, detail < 0 ? 0 : detail, out, err);
        }
    }
    mesh_builder b = {0};
    if (strcmp(name, primitive_names[0]) == 0) {
        if (detail > 8) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "sphere: detail %d: at most 8", detail);
        }
        return mesh_icosphere(detail < 0 ? 3 : detail, out, err);
    } else if (strcmp(name, primitive_names[1]) == 0) {
        const double lo[3] = {-1, -1, -1}, hi[3] = {1, 1, 1};
        builder_box(&b, lo, hi);
    } else if (strcmp(name, primitive_names[2]) == 0) {
        int n = detail < 1 ? 1 : detail;
        if (n > 4096) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "plane: detail %d: at most 4096 cells a side",
                                   detail);
        }
        builder_grid(&b, -1, -1, 1, 1, 0, n, n);
    } else if (strcmp(name, primitive_names[3]) == 0) {
        int seg = detail < 3 ? 32 : detail;
        if (seg > 1 << 20) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "cylinder: detail %d: too many segments",
                                   detail);
        }
        builder_cylinder(&b, seg);
    } else {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "unknown built-in object '%s' (valid: %s)", name,
                               lanes_builtin_object_names());
    }
    return builder_finish(&b, out, name, err);
}

double lanes_builtin_object_triangles(const char *name, int detail)
{
    for (size_t i = 0; i < N_CGAL; i++) {
        char path[4096];
        double faces = 0;
        lanes_error ignored;
        if (strcmp(name, cgal_meshes[i].name) != 0) continue;
        if (detail > 4 || !mesh_path(cgal_meshes[i].file, path, sizeof path) ||
            lanes_mesh_declared_faces(path, &faces, &ignored) != LANES_OK)
            return 0;
        return faces * pow(4.0, detail < 0 ? 0 : detail); /* Loop subdivision: 4 per step */
    }
    if (strcmp(name, primitive_names[0]) == 0) return detail > 8 ? 0 : 20.0 * pow(4.0, detail < 0 ? 3 : detail);
    if (strcmp(name, primitive_names[1]) == 0) return 12;
    if (strcmp(name, primitive_names[2]) == 0) {
        double n = detail < 1 ? 1 : detail;
        return n > 4096 ? 0 : 2 * n * n;
    }
    if (strcmp(name, primitive_names[3]) == 0) {
        double seg = detail < 3 ? 32 : detail;
        return seg > 1 << 20 ? 0 : 4 * seg; /* the side's quads and the two caps' fans */
    }
    return 0;
}

/* ---- scene assembly helpers ---- */

static lanes_status add_mat(lanes_scene *s, const char *name, lanes_material_kind kind, double r, double g,
                            double bl, uint32_t *idx, lanes_error *err)
{
    lanes_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "%s", name);
    m.kind = kind;
    m.ior = 1.5f;
    float c[3] = {(float)r, (float)g, (float)bl};
    if (kind == LANES_MAT_EMISSIVE)
        memcpy(m.emission, c, sizeof c);
    else
        memcpy(m.color, c, sizeof c);
    return lanes_scene_add_material(s, &m, idx, err);
}

static lanes_status add_point(lanes_scene *s, double x, double y, double z, double i, lanes_error *err)
{
    lanes_point_light l = {{(float)x, (float)y, (float)z}, {(float)i, (float)i, (float)i}};
    return lanes_scene_add_point_light(s, &l, err);
}

static void set_camera(lanes_scene *s, double ex, double ey, double ez, double tx, double ty,
                       double tz, double fov)
{
    lanes_camera *c = &s->camera;
    c->eye[0] = (float)ex;
    c->eye[1] = (float)ey;
    c->eye[2] = (float)ez;
    c->target[0] = (float)tx;
    c->target[1] = (float)ty;
    c->target[2] = (float)tz;
    c->up[0] = 0.0f;
    c->up[1] = 1.0f;
    c->up[2] = 0.0f;
    c->fov_y_degrees = (float)fov;
    c->width = 512; /* the thesis rendered every scene at 512x512 */
    c->height = 512;
}

/* Places a mesh: scale, then rotate about +y, then translate. */
static lanes_status place(lanes_scene *s, const lanes_mesh *m, double scale, double yaw, double x, double y,
                          double z, uint32_t mat, const char *what, lanes_error *err)
{
    lanes_xform r, x3;
    const double up[3] = {0, 1, 0}, t[3] = {x, y, z}, sc[3] = {scale, scale, scale};
    lanes_xform_rotation(&r, up, yaw);
    lanes_xform_trs(&x3, t, &r, sc);
    return lanes_scene_add_mesh(s, m, &x3, mat, what, err);
}

static lanes_status add_builder(lanes_scene *s, mesh_builder *b, uint32_t mat, const char *what, lanes_error *err)
{
    lanes_status status;
    lanes_mesh m;
    if ((status = builder_finish(b, &m, what, err)) != LANES_OK) return status;
    status = lanes_scene_add_mesh(s, &m, NULL, mat, what, err);
    lanes_mesh_free(&m);
    return status;
}

lanes_status lanes_scene_add_area_light_quad(lanes_scene *s, const lanes_area_light *l, bool visible,
                                             lanes_error *err)
{
    lanes_status status;
    if ((status = lanes_scene_add_area_light(s, l, err)) != LANES_OK) return status;
    if (!visible) return LANES_OK;
    lanes_material m;
    memset(&m, 0, sizeof m);
    snprintf(m.name, sizeof m.name, "@area_light_%zu", s->area_light_count - 1);
    m.kind = LANES_MAT_EMISSIVE;
    m.ior = 1.0f;
    memcpy(m.emission, l->emission, sizeof m.emission);
    uint32_t mi;
    if ((status = lanes_scene_add_material(s, &m, &mi, err)) != LANES_OK) return status;
    float p[4][3];
    for (int a = 0; a < 3; a++) {
        p[0][a] = l->corner[a];
        p[1][a] = l->corner[a] + l->edge_u[a];
        p[2][a] = l->corner[a] + l->edge_u[a] + l->edge_v[a];
        p[3][a] = l->corner[a] + l->edge_v[a];
    }
    /* Both triangles wind so their normal is edge_u x edge_v, the side the
     * light emits on. */
    float t0[9], t1[9];
    memcpy(t0, p[0], 12);
    memcpy(t0 + 3, p[1], 12);
    memcpy(t0 + 6, p[2], 12);
    memcpy(t1, p[0], 12);
    memcpy(t1 + 3, p[2], 12);
    memcpy(t1 + 6, p[3], 12);
    if ((status = lanes_scene_add_triangle(s, t0, mi, err)) != LANES_OK) return status;
    return lanes_scene_add_triangle(s, t1, mi, err);
}

/* ---- default: a Cornell-like room, no download needed ---- */

static lanes_status scene_default(lanes_scene *s, lanes_error *err)
{
    lanes_status status;
    uint32_t white, red, green, mirror, glass;
    if ((status = add_mat(s, "white", LANES_MAT_DIFFUSE, 0.73, 0.73, 0.73, &white, err)) != LANES_OK ||
        (status = add_mat(s, "red", LANES_MAT_DIFFUSE, 0.63, 0.065, 0.05, &red, err)) != LANES_OK ||
        (status = add_mat(s, "green", LANES_MAT_DIFFUSE, 0.14, 0.45, 0.091, &green, err)) != LANES_OK ||
        (status = add_mat(s, "mirror", LANES_MAT_MIRROR, 0.95, 0.95, 0.95, &mirror, err)) != LANES_OK ||
        (status = add_mat(s, "glass", LANES_MAT_GLASS, 1.0, 1.0, 1.0, &glass, err)) != LANES_OK)
        return status;
    s->materials[glass].ior = 1.5f;
    /* Room x in [-1, 1], y in [0, 2], z in [-1, 1], open towards +z. */
    mesh_builder room = {0}, left = {0}, right = {0};
    uint32_t v[8];
    for (int i = 0; i < 8; i++)
        v[i] = builder_vertex(&room, i & 1 ? 1 : -1, i & 2 ? 2 : 0, i & 4 ? 1 : -1);
    builder_quad(&room, v[0], v[4], v[5], v[1]); /* floor, facing up */
    builder_quad(&room, v[2], v[3], v[7], v[6]); /* ceiling, facing down */
    builder_quad(&room, v[0], v[1], v[3], v[2]); /* back wall, facing +z */
    /* Side walls face into the room. */
    uint32_t a = builder_vertex(&left, -1, 0, -1), b = builder_vertex(&left, -1, 0, 1), c = builder_vertex(&left, -1, 2, 1),
             d = builder_vertex(&left, -1, 2, -1);
    builder_quad(&left, a, d, c, b);
    a = builder_vertex(&right, 1, 0, -1);
    b = builder_vertex(&right, 1, 2, -1);
    c = builder_vertex(&right, 1, 2, 1);
    d = builder_vertex(&right, 1, 0, 1);
    builder_quad(&right, a, d, c, b);
    status = add_builder(s, &room, white, "default room", err);
    if (status == LANES_OK) status = add_builder(s, &left, red, "default room", err);
    if (status == LANES_OK) status = add_builder(s, &right, green, "default room", err);
    lanes_mesh_free(&room.m);
    lanes_mesh_free(&left.m);
    lanes_mesh_free(&right.m);
    if (status != LANES_OK) return status;
    /* A tall box, turned. */
    mesh_builder box = {0};
    const double lo[3] = {-1, 0, -1}, hi[3] = {1, 1, 1};
    builder_box(&box, lo, hi);
    lanes_mesh boxm, sph;
    if ((status = builder_finish(&box, &boxm, "box", err)) != LANES_OK) return status;
    lanes_xform r, x;
    const double up[3] = {0, 1, 0}, t[3] = {-0.38, 0, -0.3}, sc[3] = {0.28, 1.2, 0.28};
    lanes_xform_rotation(&r, up, 20.0);
    lanes_xform_trs(&x, t, &r, sc);
    status = lanes_scene_add_mesh(s, &boxm, &x, white, "default box", err);
    lanes_mesh_free(&boxm);
    if (status != LANES_OK || (status = mesh_icosphere(3, &sph, err)) != LANES_OK) return status;
    status = place(s, &sph, 0.3, 0, 0.45, 0.3, -0.1, mirror, "default sphere", err);
    if (status == LANES_OK) status = place(s, &sph, 0.3, 0, -0.25, 0.3, 0.5, glass, "default sphere", err);
    lanes_mesh_free(&sph);
    if (status != LANES_OK) return status;
    lanes_area_light al = {{-0.25f, 1.98f, -0.2f}, {0.5f, 0, 0}, {0, 0, 0.4f}, {8, 7, 5.5f}};
    /* edge_u x edge_v = (0.5,0,0) x (0,0,0.4) = (0,-0.2,0): emits downward. */
    if ((status = lanes_scene_add_area_light_quad(s, &al, true, err)) != LANES_OK ||
        (status = add_point(s, 0.0, 1.6, 0.7, 1.2, err)) != LANES_OK)
        return status;
    set_camera(s, 0.0, 1.0, 3.9, 0.0, 1.0, 0.0, 38.0);
    return LANES_OK;
}

/* ---- dragon: the thesis' fully diffuse scene ---- */

static lanes_status ground(lanes_scene *s, double half, uint32_t mat, lanes_error *err)
{
    mesh_builder b = {0};
    builder_grid(&b, -half, -half, half, half, 0.0, 1, 1);
    return add_builder(s, &b, mat, "ground", err);
}

static lanes_status scene_dragon(lanes_scene *s, lanes_error *err)
{
    lanes_status status;
    uint32_t stone, floor;
    if ((status = add_mat(s, "dragon", LANES_MAT_DIFFUSE, 0.75, 0.62, 0.42, &stone, err)) != LANES_OK ||
        (status = add_mat(s, "ground", LANES_MAT_DIFFUSE, 0.5, 0.5, 0.55, &floor, err)) != LANES_OK)
        return status;
    lanes_mesh d;
    /* CGAL's dragon has 19,994 triangles; one Loop step gives 79,976, near
     * the thesis' 100K, and keeps the surface smooth. */
    if ((status = lanes_builtin_object("dragon", 1, &d, err)) != LANES_OK) return status;
    status = place(s, &d, 2.0, -25.0, 0, 0, 0, stone, "dragon", err);
    lanes_mesh_free(&d);
    if (status != LANES_OK || (status = ground(s, 1.5, floor, err)) != LANES_OK ||
        (status = add_point(s, 2.5, 4.5, 3.5, 30.0, err)) != LANES_OK)
        return status;
    set_camera(s, 2.2, 1.9, 4.2, 0.0, 0.9, 0.0, 36.0);
    return LANES_OK;
}

/* ---- sponza-bunny: a procedural atrium with a mirror bunny ---- */

/* Atrium dimensions (meters): courtyard x in [-AX, AX], z in [-AZ, AZ],
 * bays of BAY between column centers, galleries GAL deep behind the
 * arcades, two stories. */
#define AX 13.5
#define AZ 4.5
#define BAY 3.0
#define GAL 3.0
#define ARCH_SEG 24
#define COL_SEG 24
#define COL_ROWS 16

/* A column at (x, z) from y0 to y1: base block, a shaft with entasis and
 * a capital block. */
static void add_column(mesh_builder *b, double x, double z, double y0, double y1, double r)
{
    double base_h = 0.22, cap_h = 0.2;
    const double blo[3] = {x - 1.35 * r, y0, z - 1.35 * r},
                 bhi[3] = {x + 1.35 * r, y0 + base_h, z + 1.35 * r};
    builder_box(b, blo, bhi);
    const double clo[3] = {x - 1.3 * r, y1 - cap_h, z - 1.3 * r},
                 chi[3] = {x + 1.3 * r, y1, z + 1.3 * r};
    builder_box(b, clo, chi);
    double prof[COL_ROWS + 1][2];
    for (int j = 0; j <= COL_ROWS; j++) {
        double u = (double)j / COL_ROWS;
        prof[j][0] = r * (1.0 - 0.12 * u * u + 0.04 * sin(PI * u));
        prof[j][1] = y0 + base_h + u * (y1 - cap_h - y0 - base_h);
    }
    builder_lathe(b, x, z, (const double(*)[2])prof, COL_ROWS + 1, COL_SEG);
}

/* One bay of an arcade wall along the local u axis: from column center u0
 * to u1 (at wall coordinate w, thickness th, normal along the other
 * horizontal axis), a semicircular opening springing at y0 and the wall up
 * to y1. `along_x` chooses the orientation. */
static void add_arch_bay(mesh_builder *b, bool along_x, double w, double u0, double u1, double y0,
                         double y1, double th, double pier)
{
    double um = 0.5 * (u0 + u1), R = 0.5 * (u1 - u0) - pier;
#define P(u, y, ww) (along_x ? builder_vertex(b, (u), (y), (ww)) : builder_vertex(b, (ww), (y), (u)))
    for (int side = 0; side < 2; side++) {
        double ww = w + (side ? 0.5 : -0.5) * th;
        /* Vertical strips from the intrados up to the top of the wall, plus
         * the solid piers over the capitals. */
        uint32_t prev_a = 0, prev_t = 0;
        for (int i = 0; i <= ARCH_SEG; i++) {
            double ang = PI * (1.0 - (double)i / ARCH_SEG);
            double u = um + R * cos(ang), y = y0 + R * sin(ang);
            uint32_t a = P(u, y, ww), t = P(u, y1, ww);
            if (i > 0) {
                if (side ^ !along_x)
                    builder_quad(b, prev_a, a, t, prev_t);
                else
                    builder_quad(b, prev_a, prev_t, t, a);
            }
            prev_a = a;
            prev_t = t;
        }
        for (int k = 0; k < 2; k++) {
            double ua = k ? um + R : u0, ub = k ? u1 : um - R;
            uint32_t p0 = P(ua, y0, ww), p1 = P(ub, y0, ww), p2 = P(ub, y1, ww), p3 = P(ua, y1, ww);
            if (side ^ !along_x)
                builder_quad(b, p0, p1, p2, p3);
            else
                builder_quad(b, p0, p3, p2, p1);
        }
    }
    /* The intrados: the curved underside of the arch. */
    uint32_t pa = 0, pb = 0;
    for (int i = 0; i <= ARCH_SEG; i++) {
        double ang = PI * (1.0 - (double)i / ARCH_SEG);
        double u = um + R * cos(ang), y = y0 + R * sin(ang);
        uint32_t a = P(u, y, w - 0.5 * th), c = P(u, y, w + 0.5 * th);
        if (i > 0) {
            if (along_x)
                builder_quad(b, pa, pb, c, a);
            else
                builder_quad(b, pa, a, c, pb);
        }
        pa = a;
        pb = c;
    }
#undef P
}

/* A banner hanging in an upper arch: a cloth grid with soft folds. */
static void add_banner(mesh_builder *b, double x, double z, double y_top, double width, double height,
                       double facing)
{
    const int nu = 16, nv = 24;
    uint32_t base = (uint32_t)b->m.vertex_count;
    for (int j = 0; j <= nv; j++)
        for (int i = 0; i <= nu; i++) {
            double u = (double)i / nu, v = (double)j / nv;
            double fold = 0.08 * sin(6.0 * PI * u) * (0.3 + v) + 0.25 * v * v;
            builder_vertex(b, x + (u - 0.5) * width, y_top - v * height, z + facing * fold);
        }
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            uint32_t a = base + (uint32_t)(j * (nu + 1) + i);
            builder_quad(b, a, a + 1, a + (uint32_t)(nu + 2), a + (uint32_t)(nu + 1));
        }
}

static lanes_status scene_sponza(lanes_scene *s, lanes_error *err)
{
    lanes_status status;
    uint32_t stone, floor, cloth[3], mirror;
    if ((status = add_mat(s, "stone", LANES_MAT_DIFFUSE, 0.78, 0.72, 0.6, &stone, err)) != LANES_OK ||
        (status = add_mat(s, "floor", LANES_MAT_DIFFUSE, 0.55, 0.5, 0.45, &floor, err)) != LANES_OK ||
        (status = add_mat(s, "cloth-red", LANES_MAT_DIFFUSE, 0.6, 0.1, 0.08, &cloth[0], err)) != LANES_OK ||
        (status = add_mat(s, "cloth-green", LANES_MAT_DIFFUSE, 0.1, 0.4, 0.15, &cloth[1], err)) != LANES_OK ||
        (status = add_mat(s, "cloth-blue", LANES_MAT_DIFFUSE, 0.1, 0.15, 0.5, &cloth[2], err)) != LANES_OK ||
        (status = add_mat(s, "mirror", LANES_MAT_MIRROR, 0.9, 0.9, 0.9, &mirror, err)) != LANES_OK)
        return status;
    mesh_builder st = {0}, fl = {0}, cl[3];
    memset(cl, 0, sizeof cl);
    const double story_y[3] = {0.0, 4.8, 9.6}; /* floor of each story; roof at 13.2 */
    const double col_r[2] = {0.3, 0.24}, spring[2] = {3.0, 7.6};
    /* Floors: courtyard + galleries, and the upper gallery floor. */
    builder_grid(&fl, -AX - GAL, -AZ - GAL, AX + GAL, AZ + GAL, 0.0, 24, 10);
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        /* Upper gallery floor slabs (both faces) along the long sides. */
        double z0 = sgn * AZ, z1 = sgn * (AZ + GAL);
        double lo[3] = {-AX - GAL, story_y[1] - 0.3, fmin(z0, z1)},
               hi[3] = {AX + GAL, story_y[1], fmax(z0, z1)};
        builder_box(&st, lo, hi);
        double lo2[3] = {-AX - GAL, story_y[2] - 0.3, fmin(z0, z1)},
               hi2[3] = {AX + GAL, story_y[2], fmax(z0, z1)};
        builder_box(&st, lo2, hi2);
        /* Short sides. */
        double x0 = sgn * AX, x1 = sgn * (AX + GAL);
        double lo3[3] = {fmin(x0, x1), story_y[1] - 0.3, -AZ},
               hi3[3] = {fmax(x0, x1), story_y[1], AZ};
        builder_box(&st, lo3, hi3);
        double lo4[3] = {fmin(x0, x1), story_y[2] - 0.3, -AZ},
               hi4[3] = {fmax(x0, x1), story_y[2], AZ};
        builder_box(&st, lo4, hi4);
        /* Outer walls, full height. */
        double lo5[3] = {-AX - GAL - 0.4, 0, sgn > 0 ? AZ + GAL : -AZ - GAL - 0.4},
               hi5[3] = {AX + GAL + 0.4, 13.2, sgn > 0 ? AZ + GAL + 0.4 : -AZ - GAL};
        builder_box(&st, lo5, hi5);
        double lo6[3] = {sgn > 0 ? AX + GAL : -AX - GAL - 0.4, 0, -AZ - GAL},
               hi6[3] = {sgn > 0 ? AX + GAL + 0.4 : -AX - GAL, 13.2, AZ + GAL};
        builder_box(&st, lo6, hi6);
        /* Top story: a solid wall with a cornice over the arcades. */
        double lo7[3] = {-AX - 0.3, story_y[2], sgn * AZ - 0.3},
               hi7[3] = {AX + 0.3, 13.2, sgn * AZ + 0.3};
        builder_box(&st, lo7, hi7);
        double lo8[3] = {sgn * AX - 0.3, story_y[2], -AZ}, hi8[3] = {sgn * AX + 0.3, 13.2, AZ};
        builder_box(&st, lo8, hi8);
        double lo9[3] = {-AX - GAL, 13.2, fmin(sgn * (AZ - 0.6), sgn * (AZ + GAL))},
               hi9[3] = {AX + GAL, 13.5, fmax(sgn * (AZ - 0.6), sgn * (AZ + GAL))};
        builder_box(&st, lo9, hi9);
    }
    for (int story = 0; story < 2; story++) {
        double y0 = story_y[story], r = col_r[story], ys = spring[story];
        double ytop = story_y[story + 1];
        int nx = (int)(2 * AX / BAY + 0.5), nz = (int)(2 * AZ / BAY + 0.5);
        for (int sgn = -1; sgn <= 1; sgn += 2) {
            for (int i = 0; i <= nx; i++)
                add_column(&st, -AX + BAY * i, sgn * AZ, y0, ys, r);
            for (int j = 1; j < nz; j++)
                add_column(&st, sgn * AX, -AZ + BAY * j, y0, ys, r);
            for (int i = 0; i < nx; i++)
                add_arch_bay(&st, true, sgn * AZ, -AX + BAY * i, -AX + BAY * (i + 1), ys, ytop, 0.6,
                             1.3 * r);
            for (int j = 0; j < nz; j++)
                add_arch_bay(&st, false, sgn * AX, -AZ + BAY * j, -AZ + BAY * (j + 1), ys, ytop,
                             0.6, 1.3 * r);
            /* Banners in the upper arches of the long sides, hung just
             * inside the courtyard, colors cycling. */
            if (story == 1)
                for (int i = 0; i < nx; i++)
                    add_banner(&cl[(i + (sgn > 0)) % 3], -AX + BAY * (i + 0.5), sgn * (AZ - 0.45),
                               ys + 0.9, 1.7, 3.2, -sgn);
        }
    }
    status = add_builder(s, &fl, floor, "atrium floor", err);
    if (status == LANES_OK) status = add_builder(s, &st, stone, "atrium", err);
    for (int k = 0; k < 3 && status == LANES_OK; k++)
        status = add_builder(s, &cl[k], cloth[k], "atrium banners", err);
    lanes_mesh_free(&fl.m);
    lanes_mesh_free(&st.m);
    for (int k = 0; k < 3; k++)
        lanes_mesh_free(&cl[k].m);
    if (status != LANES_OK) return status;
    lanes_mesh bunny;
    if ((status = lanes_builtin_object("bunny", 0, &bunny, err)) != LANES_OK) return status;
    status = place(s, &bunny, 5.0, -60.0, 0.0, 0.0, 0.0, mirror, "bunny", err);
    lanes_mesh_free(&bunny);
    if (status != LANES_OK || (status = add_point(s, -6.0, 10.5, 0.5, 90.0, err)) != LANES_OK ||
        (status = add_point(s, 7.0, 8.0, -1.5, 60.0, err)) != LANES_OK)
        return status;
    set_camera(s, -10.0, 2.6, 0.8, 0.0, 2.7, 0.0, 60.0);
    return LANES_OK;
}

/* ---- 20 bunnies ---- */

static lanes_status scene_bunnies(lanes_scene *s, bool small, lanes_error *err)
{
    lanes_status status;
    uint32_t diffuse, mirror, floor;
    if ((status = add_mat(s, "bunny", LANES_MAT_DIFFUSE, 0.7, 0.65, 0.55, &diffuse, err)) != LANES_OK ||
        (status = add_mat(s, "mirror", LANES_MAT_MIRROR, 0.9, 0.9, 0.9, &mirror, err)) != LANES_OK ||
        (status = add_mat(s, "ground", LANES_MAT_DIFFUSE, 0.45, 0.5, 0.45, &floor, err)) != LANES_OK)
        return status;
    lanes_mesh bunny;
    if ((status = lanes_builtin_object("bunny", 0, &bunny, err)) != LANES_OK) return status;
    if (small) {
        /* 75,408 -> about 4K triangles each; the same layout as the full
         * scene, so it stands in for it in quick tests. */
        lanes_mesh coarse;
        status = lanes_mesh_decimate(&bunny, 26, &coarse, err);
        lanes_mesh_free(&bunny);
        if (status != LANES_OK) return status;
        bunny = coarse;
    }
    /* The thesis spreads its 20 bunnies over a triangle: rejection-sample
     * positions in the triangle (-9,5) (9,5) (0,-12) of the xz plane with a
     * minimum spacing, a random turn each, and a shuffled half of them
     * mirrors, so the specular ones are scattered, not grouped. */
    pcg32 rng;
    pcg32_seed(&rng, 20140101u, 20u);
    double pos[20][2];
    int n = 0, tries = 0;
    const double A[2] = {-9, 5}, B[2] = {9, 5}, C[2] = {0, -12};
    while (n < 20) {
        double u = rnd(&rng), v = rnd(&rng);
        if (u + v > 1.0) {
            u = 1.0 - u;
            v = 1.0 - v;
        }
        double x = A[0] + u * (B[0] - A[0]) + v * (C[0] - A[0]);
        double z = A[1] + u * (B[1] - A[1]) + v * (C[1] - A[1]);
        bool far_enough = true;
        double min_d = ++tries < 100000 ? 2.6 : 1.8;
        for (int k = 0; k < n; k++) {
            double dx = pos[k][0] - x, dz = pos[k][1] - z;
            far_enough = far_enough && dx * dx + dz * dz >= min_d * min_d;
        }
        if (far_enough) {
            pos[n][0] = x;
            pos[n][1] = z;
            n++;
        }
    }
    int is_mirror[20];
    for (int i = 0; i < 20; i++)
        is_mirror[i] = i < 10;
    for (int i = 19; i > 0; i--) {
        int j = (int)(pcg32_next(&rng) % (uint32_t)(i + 1));
        int t = is_mirror[i];
        is_mirror[i] = is_mirror[j];
        is_mirror[j] = t;
    }
    for (int i = 0; i < 20 && status == LANES_OK; i++) {
        double yaw = 360.0 * rnd(&rng);
        status = place(s, &bunny, 2.4, yaw, pos[i][0], 0.0, pos[i][1], is_mirror[i] ? mirror : diffuse,
                       "bunny", err);
    }
    lanes_mesh_free(&bunny);
    if (status != LANES_OK) return status;
    /* The ground: the triangle itself, enlarged around its centroid. */
    float g[9];
    const double cx = (A[0] + B[0] + C[0]) / 3.0, cz = (A[1] + B[1] + C[1]) / 3.0;
    const double *corner[3] = {A, B, C};
    for (int k = 0; k < 3; k++) {
        g[3 * k] = (float)(cx + 1.6 * (corner[k][0] - cx));
        g[3 * k + 1] = 0.0f;
        g[3 * k + 2] = (float)(cz + 1.6 * (corner[k][1] - cz));
    }
    /* A, B, C runs clockwise seen from above; swap to face +y. */
    float t3[3];
    memcpy(t3, g + 3, sizeof t3);
    memcpy(g + 3, g + 6, sizeof t3);
    memcpy(g + 6, t3, sizeof t3);
    if ((status = lanes_scene_add_triangle(s, g, floor, err)) != LANES_OK ||
        (status = add_point(s, 5.0, 14.0, 8.0, 260.0, err)) != LANES_OK)
        return status;
    set_camera(s, 0.0, 8.0, 13.5, 0.0, 0.4, -3.2, 50.0);
    return LANES_OK;
}

/* ---- hairball ---- */

/* Thin tubes (triangular cross-section) along smooth random curves inside
 * the unit sphere, all mirror. Curves: a unit-speed walk whose direction
 * turns by a slowly varying curvature vector; near the sphere it is
 * steered back inside. Tubes follow parallel-transport frames so they do
 * not twist. */
#define HAIR_SIDES 3
#define HAIR_SEGMENTS 320

static lanes_status scene_hairball(lanes_scene *s, bool small, lanes_error *err)
{
    lanes_status status;
    uint32_t mirror;
    if ((status = add_mat(s, "hair", LANES_MAT_MIRROR, 0.85, 0.8, 0.7, &mirror, err)) != LANES_OK)
        return status;
    const int curves = small ? 50 : 1500;
    const double radius = 0.006, step = 0.012;
    size_t tris = (size_t)curves * HAIR_SEGMENTS * HAIR_SIDES * 2;
    if ((status = lanes_scene_reserve_triangles(s, tris, err)) != LANES_OK) return status;
    pcg32 rng;
    pcg32_seed(&rng, 0x4a1eba11u, 7u);
    float ring[2][HAIR_SIDES][3];
    double ring_cos[HAIR_SIDES], ring_sin[HAIR_SIDES];
    for (int j = 0; j < HAIR_SIDES; j++) {
        ring_cos[j] = cos(2.0 * PI * j / HAIR_SIDES);
        ring_sin[j] = sin(2.0 * PI * j / HAIR_SIDES);
    }
    float *out = s->verts + 9 * s->triangle_count;
    for (int c = 0; c < curves; c++) {
        double p[3], d[3], k[3] = {0, 0, 0}, n[3], bnorm[3];
        rnd_ball(&rng, p);
        for (int a = 0; a < 3; a++)
            p[a] *= 0.9;
        do
            rnd_ball(&rng, d);
        while (dot3(d, d) < 1e-4);
        normalize3(d);
        /* Any vector not parallel to d starts the frame. */
        double helper[3] = {fabs(d[0]) < 0.9 ? 1.0 : 0.0, fabs(d[0]) < 0.9 ? 0.0 : 1.0, 0.0};
        cross3(d, helper, n);
        normalize3(n);
        cross3(d, n, bnorm);
        for (int i = 0; i <= HAIR_SEGMENTS; i++) {
            float(*r)[3] = ring[i & 1];
            for (int j = 0; j < HAIR_SIDES; j++) {
                for (int a = 0; a < 3; a++)
                    r[j][a] =
                        (float)(p[a] + radius * (ring_cos[j] * n[a] + ring_sin[j] * bnorm[a]));
            }
            if (i > 0) {
                float(*q)[3] = ring[(i - 1) & 1];
                for (int j = 0; j < HAIR_SIDES; j++) {
                    int j1 = (j + 1) % HAIR_SIDES;
                    const float *quad[4] = {q[j], q[j1], r[j1], r[j]};
                    memcpy(out + 0, quad[0], 12);
                    memcpy(out + 3, quad[1], 12);
                    memcpy(out + 6, quad[2], 12);
                    memcpy(out + 9, quad[0], 12);
                    memcpy(out + 12, quad[2], 12);
                    memcpy(out + 15, quad[3], 12);
                    out += 18;
                }
            }
            /* Advance: the curvature vector drifts, the direction turns by
             * it, and the walk is pulled back when it nears the surface. */
            for (int a = 0; a < 3; a++)
                k[a] = 0.94 * k[a] + 0.6 * (2.0 * rnd(&rng) - 1.0);
            double nd[3], rad = sqrt(dot3(p, p)), outward = rad > 0.0 ? dot3(p, d) / rad : 0.0;
            /* Past 0.8 of the radius, a heading outward is bent back, more
             * strongly the further out: the walk stays inside the sphere
             * (up to the tube radius) without a kink. */
            double pull = rad > 0.8 && outward > 0.0 ? 2.0 * (rad - 0.8) / 0.2 * outward : 0.0;
            for (int a = 0; a < 3; a++)
                nd[a] = d[a] + step * 6.0 * k[a] - (pull > 0.0 ? pull * p[a] / rad : 0.0);
            normalize3(nd);
            /* Parallel transport: rotate n by the turn from d to nd
             * (project, re-orthonormalize: exact enough for small turns). */
            double proj = dot3(n, nd);
            for (int a = 0; a < 3; a++)
                n[a] -= proj * nd[a];
            normalize3(n);
            cross3(nd, n, bnorm);
            memcpy(d, nd, sizeof d);
            for (int a = 0; a < 3; a++)
                p[a] += step * d[a];
        }
    }
    for (size_t t = s->triangle_count; t < s->triangle_count + tris; t++)
        s->material_of[t] = mirror;
    s->triangle_count += tris;
    if ((status = add_point(s, 3.0, 4.0, 5.0, 40.0, err)) != LANES_OK) return status;
    set_camera(s, 0.0, 0.0, 3.3, 0.0, 0.0, 0.0, 38.0);
    return LANES_OK;
}

/* ---- the table ---- */

typedef struct builtin_scene {
    lanes_builtin_info info;
    lanes_status (*make)(lanes_scene *s, lanes_error *err);
} builtin_scene;

static lanes_status make_bunnies(lanes_scene *s, lanes_error *err)
{
    return scene_bunnies(s, false, err);
}
static lanes_status make_bunnies_small(lanes_scene *s, lanes_error *err)
{
    return scene_bunnies(s, true, err);
}
static lanes_status make_hairball(lanes_scene *s, lanes_error *err)
{
    return scene_hairball(s, false, err);
}
static lanes_status make_hairball_small(lanes_scene *s, lanes_error *err)
{
    return scene_hairball(s, true, err);
}

static const builtin_scene scenes[] = {
    {{"default", "Cornell-like room: mirror and glass spheres, a box, point + area light", false},
     scene_default},
    {{"dragon", "diffuse CGAL Chinese dragon (one Loop step) on a ground square, 1 point light",
      true},
     scene_dragon},
    {{"sponza-bunny", "procedural two-story atrium, mirror bunny in the middle, 2 point lights",
      true},
     scene_sponza},
    {{"20-bunnies", "20 bunnies (10 mirror, 10 diffuse) spread over a ground triangle", true},
     make_bunnies},
    {{"20-bunnies-small", "20-bunnies with decimated bunnies (~4K triangles each)", true},
     make_bunnies_small},
    {{"hairball", "1500 thin mirror tubes along random curves in a sphere", false}, make_hairball},
    {{"hairball-small", "hairball with 50 tubes", false}, make_hairball_small},
};
#define N_SCENES (sizeof scenes / sizeof scenes[0])

size_t lanes_builtin_scene_count(void)
{
    return N_SCENES;
}

const lanes_builtin_info *lanes_builtin_scene_info(size_t i)
{
    return i < N_SCENES ? &scenes[i].info : NULL;
}

lanes_status lanes_builtin_scene(const char *name, lanes_scene *out, lanes_error *err)
{
    lanes_status status;
    lanes_scene_init(out);
    if ((status = lanes_scene_limit_to_memory(out, err)) != LANES_OK) return status;
    for (size_t i = 0; i < N_SCENES; i++) {
        if (strcmp(name, scenes[i].info.name) != 0)
            continue;
        snprintf(out->name, sizeof out->name, "%s", name);
        lanes_error sub;
        if (scenes[i].make(out, &sub) != LANES_OK) {
            lanes_scene_free(out);
            return lanes_error_set(err, sub.status, "scene '%s': %s", name, sub.message);
        }
        return LANES_OK;
    }
    char names[512] = "";
    for (size_t i = 0; i < N_SCENES; i++) {
        size_t len = strlen(names);
        snprintf(names + len, sizeof names - len, "%s%s", i ? ", " : "", scenes[i].info.name);
    }
    return lanes_error_set(err, LANES_ERR_BAD_INPUT, "unknown built-in scene '%s' (valid: %s)", name, names);
}
