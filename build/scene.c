/* The scene container: growth, bounds, validation, placing meshes.
 *
 * Compiled for the x86-64 baseline. */
#include "build/scene.h"

#include "build/grow_array.h"
#include "build/memory_limit.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool finite3(const float v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static bool within_bound(const float v[3])
{
    return fabsf(v[0]) <= LANES_SCENE_MAX_COORD && fabsf(v[1]) <= LANES_SCENE_MAX_COORD &&
           fabsf(v[2]) <= LANES_SCENE_MAX_COORD;
}

void lanes_scene_init(lanes_scene *scene)
{
    memset(scene, 0, sizeof *scene);
    lanes_camera *c = &scene->camera;
    c->eye[2] = 5.0f;
    c->up[1] = 1.0f;
    c->fov_y_degrees = 45.0f;
    c->width = 512;
    c->height = 512;
    scene->accuracy = -1;
}

void lanes_scene_free(lanes_scene *scene)
{
    if (!scene)
        return;
    free(scene->verts);
    free(scene->material_of);
    free(scene->materials);
    free(scene->point_lights);
    free(scene->area_lights);
    lanes_scene_init(scene);
}

void lanes_scene_bounds(const lanes_scene *scene, float min[3], float max[3])
{
    for (int a = 0; a < 3; a++) {
        min[a] = INFINITY;
        max[a] = -INFINITY;
    }
    size_t n = scene->triangle_count * 3;
    for (size_t v = 0; v < n; v++) {
        const float *p = scene->verts + 3 * v;
        /* One bad vertex must not turn the bounds into NaN: the camera
         * framing and the BVH root both derive from them. */
        if (!isfinite(p[0]) || !isfinite(p[1]) || !isfinite(p[2]))
            continue;
        for (int a = 0; a < 3; a++) {
            if (p[a] < min[a])
                min[a] = p[a];
            if (p[a] > max[a])
                max[a] = p[a];
        }
    }
}

float lanes_scene_epsilon(const lanes_scene *scene)
{
    float lo[3], hi[3];
    lanes_scene_bounds(scene, lo, hi);
    double diag2 = 0.0;
    for (int a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) return 0.0f;
        diag2 += ((double)hi[a] - lo[a]) * ((double)hi[a] - lo[a]);
    }
    return (float)(1e-5 * sqrt(diag2));
}

static bool color_ok(const float c[3])
{
    return finite3(c) && c[0] >= 0.0f && c[1] >= 0.0f && c[2] >= 0.0f;
}

/* A reflectance: a fraction of the light, so no channel above 1. */
static bool reflectance_ok(const float c[3]) { return color_ok(c) && c[0] <= 1.0f && c[1] <= 1.0f && c[2] <= 1.0f; }

/* What is wrong with a material's parameters, or NULL. */
static const char *material_problem(const lanes_material *m)
{
    if ((int)m->kind < 0 || (int)m->kind >= LANES_MAT_KIND_COUNT) return "an unknown kind";
    if (!reflectance_ok(m->color)) return "a color outside [0, 1]";
    if (!color_ok(m->emission)) return "a negative or non-finite emission";
    if (m->kind == LANES_MAT_GLASS && !(isfinite(m->ior) && m->ior > 0.0f)) return "an ior that is not above 0";
    if ((m->kind == LANES_MAT_CONDUCTOR || m->kind == LANES_MAT_PLASTIC || m->kind == LANES_MAT_GLASS) &&
        !(m->roughness >= 0.0f && m->roughness <= 1.0f))
        return "a roughness outside [0, 1]";
    /* rough glass cannot refract through an index-matched surface: the
     * transmission is a spike float cannot sample (trace/bsdf.h) */
    if (m->kind == LANES_MAT_GLASS && m->roughness > 0.0f && fabsf(m->ior - 1.0f) < LANES_MAT_MIN_IOR_GAP)
        return "a rough glass with an ior within 1e-4 of 1 (give it roughness 0)";
    if (m->kind == LANES_MAT_CONDUCTOR && !reflectance_ok(m->f0)) return "an f0 outside [0, 1]";
    if ((int)m->texture < LANES_MAT_TEXTURE_NONE || (int)m->texture > LANES_MAT_TEXTURE_WOOD)
        return "an unknown texture";
    if (m->texture != LANES_MAT_TEXTURE_NONE) {
        if (m->kind != LANES_MAT_DIFFUSE && m->kind != LANES_MAT_PLASTIC) return "a texture on a kind that takes none";
        if (!(isfinite(m->texture_scale) && m->texture_scale > 0.0f)) return "a texture scale that is not above 0";
        if (!reflectance_ok(m->texture_colors[0]) || !reflectance_ok(m->texture_colors[1]))
            return "a texture color outside [0, 1]";
    }
    return NULL;
}


lanes_status lanes_scene_reserve_triangles(lanes_scene *scene, size_t extra, lanes_error *err)
{
    size_t n = scene->triangle_count;
    if (extra > LANES_SCENE_MAX_TRIANGLES || n + extra > LANES_SCENE_MAX_TRIANGLES) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "too many triangles: %zu + %zu exceeds the limit of %zu", n, extra,
                               LANES_SCENE_MAX_TRIANGLES);
    }
    size_t need = n + extra;
    /* Refuse a scene while it is still small if its BVHs will not fit,
     * rather than after filling the machine. */
    if (scene->budget_note[0] && need > scene->triangle_budget) {
        char bytes[32];
        lanes_memory_size_text(bytes, sizeof bytes,
                               (double)need * (double)(LANES_SCENE_BYTES_PER_TRIANGLE + LANES_ACCEL_BYTES_PER_TRIANGLE));
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY,
                               "a scene of %zu triangles (to load and trace) needs about %s; %s", need, bytes,
                               scene->budget_note);
    }
    if (need <= scene->triangle_capacity) return LANES_OK;
    /* Both arrays share one capacity; grow a copy of it for each so a
     * failure halfway leaves triangle_capacity describing both. */
    size_t cap_v = scene->triangle_capacity, cap_m = scene->triangle_capacity;
    void *v = scene->verts, *m = scene->material_of;
    bool ok = lanes_grow_array(&v, &cap_v, need, 9 * sizeof(float));
    scene->verts = v;
    if (ok) {
        ok = lanes_grow_array(&m, &cap_m, need, sizeof(uint32_t));
        scene->material_of = m;
    }
    if (!ok) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory for %zu triangles", need);
    }
    scene->triangle_capacity = cap_v < cap_m ? cap_v : cap_m;
    return LANES_OK;
}

lanes_status lanes_scene_add_triangle(lanes_scene *scene, const float v[9], uint32_t material,
                                      lanes_error *err)
{
    lanes_status status;
    if ((status = lanes_scene_reserve_triangles(scene, 1, err)) != LANES_OK) return status;
    size_t i = scene->triangle_count++;
    memcpy(scene->verts + 9 * i, v, 9 * sizeof(float));
    scene->material_of[i] = material;
    return LANES_OK;
}

long lanes_scene_find_material(const lanes_scene *scene, const char *name)
{
    for (size_t i = 0; i < scene->material_count; i++)
        if (strcmp(scene->materials[i].name, name) == 0)
            return (long)i;
    return -1;
}

lanes_status lanes_scene_add_material(lanes_scene *scene, const lanes_material *m, uint32_t *index,
                                      lanes_error *err)
{
    if (memchr(m->name, '\0', sizeof m->name) == NULL) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "material name is not terminated within %zu bytes",
                               sizeof m->name);
    }
    if (lanes_scene_find_material(scene, m->name) >= 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "material '%s' is defined twice", m->name);
    }
    const char *problem = material_problem(m);
    if (problem) return lanes_error_set(err, LANES_ERR_BAD_INPUT, "material '%s' has %s", m->name, problem);
    if (scene->material_count >= LANES_SCENE_MAX_MATERIALS) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "material '%s': a scene takes at most %u materials", m->name,
                               LANES_SCENE_MAX_MATERIALS);
    }
    void *p = scene->materials;
    bool ok = lanes_grow_array(&p, &scene->material_capacity, scene->material_count + 1, sizeof *m);
    scene->materials = p;
    if (!ok) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory for materials");
    }
    if (index)
        *index = (uint32_t)scene->material_count;
    scene->materials[scene->material_count++] = *m;
    return LANES_OK;
}

lanes_status lanes_scene_add_point_light(lanes_scene *scene, const lanes_point_light *l, lanes_error *err)
{
    if (finite3(l->position) && !within_bound(l->position))
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "point light at (%g, %g, %g): beyond the %g a scene's coordinates may reach",
                               l->position[0], l->position[1], l->position[2], (double)LANES_SCENE_MAX_COORD);
    void *p = scene->point_lights;
    bool ok = lanes_grow_array(&p, &scene->point_light_capacity, scene->point_light_count + 1, sizeof *l);
    scene->point_lights = p;
    if (!ok) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory for lights");
    }
    scene->point_lights[scene->point_light_count++] = *l;
    return LANES_OK;
}

lanes_status lanes_scene_add_area_light(lanes_scene *scene, const lanes_area_light *l, lanes_error *err)
{
    float far[3];
    for (int a = 0; a < 3; a++) far[a] = fabsf(l->corner[a]) + fabsf(l->edge_u[a]) + fabsf(l->edge_v[a]);
    if (finite3(far) && !within_bound(far))
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "area light at (%g, %g, %g): reaches beyond the %g a scene's coordinates may reach",
                               l->corner[0], l->corner[1], l->corner[2], (double)LANES_SCENE_MAX_COORD);
    void *p = scene->area_lights;
    bool ok = lanes_grow_array(&p, &scene->area_light_capacity, scene->area_light_count + 1, sizeof *l);
    scene->area_lights = p;
    if (!ok) {
        return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "out of memory for lights");
    }
    scene->area_lights[scene->area_light_count++] = *l;
    return LANES_OK;
}

/* The largest |s p + t| over the points and extents the scene holds, in
 * double (monotone in each coordinate, so the extremes come from the
 * extremes of the input). */
static double moved_reach(double s, double t, const float v[3], double reach)
{
    for (int a = 0; a < 3; a++) reach = fmax(reach, fabs(s * v[a] + t));
    return reach;
}

lanes_status lanes_scene_scale_translate(lanes_scene *scene, double s, double t, lanes_error *err)
{
    if (!(s > 0.0) || !isfinite(s) || !isfinite(t))
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "scale %g and translation %g: the scale must be finite and positive, "
                               "the translation finite", s, t);
    float lo[3], hi[3];
    double reach = 0.0;
    if (scene->triangle_count > 0) {
        lanes_scene_bounds(scene, lo, hi);
        reach = moved_reach(s, t, hi, moved_reach(s, t, lo, reach));
    }
    for (size_t i = 0; i < scene->point_light_count; i++)
        reach = moved_reach(s, t, scene->point_lights[i].position, reach);
    for (size_t i = 0; i < scene->area_light_count; i++) {
        const lanes_area_light *l = &scene->area_lights[i];
        float far[3];
        for (int a = 0; a < 3; a++) far[a] = l->corner[a] + l->edge_u[a] + l->edge_v[a];
        reach = moved_reach(s, t, far, moved_reach(s, t, l->corner, reach));
    }
    reach = moved_reach(s, t, scene->camera.eye, moved_reach(s, t, scene->camera.target, reach));
    for (size_t i = 0; i < scene->point_light_count; i++)
        for (int a = 0; a < 3; a++)
            if (!((double)scene->point_lights[i].intensity[a] * s * s <= FLT_MAX))
                return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                       "scale %g: point light %zu's intensity, scaled by the square of "
                                       "the scale to keep its irradiance, overflows float", s, i);
    if (!(reach <= (double)LANES_SCENE_MAX_COORD))
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "scale %g and translation %g move the scene to coordinates of %g, beyond "
                               "the %g a scene's coordinates may reach", s, t, reach,
                               (double)LANES_SCENE_MAX_COORD);

    lanes_xform x;
    const double tt[3] = {t, t, t}, ss[3] = {s, s, s};
    lanes_xform_trs(&x, tt, NULL, ss);
    for (size_t i = 0; i < 3 * scene->triangle_count; i++)
        lanes_xform_apply(&x, scene->verts + 3 * i, scene->verts + 3 * i);
    for (size_t i = 0; i < scene->point_light_count; i++) {
        lanes_point_light *l = &scene->point_lights[i];
        lanes_xform_apply(&x, l->position, l->position);
        for (int a = 0; a < 3; a++) l->intensity[a] = (float)(s * s * l->intensity[a]);
    }
    for (size_t i = 0; i < scene->area_light_count; i++) {
        lanes_area_light *l = &scene->area_lights[i];
        lanes_xform_apply(&x, l->corner, l->corner);
        for (int a = 0; a < 3; a++) {
            l->edge_u[a] = (float)(s * l->edge_u[a]);
            l->edge_v[a] = (float)(s * l->edge_v[a]);
        }
    }
    lanes_xform_apply(&x, scene->camera.eye, scene->camera.eye);
    lanes_xform_apply(&x, scene->camera.target, scene->camera.target);
    return LANES_OK;
}

void lanes_scene_frame_camera(lanes_scene *s)
{
    float mn[3], mx[3];
    lanes_scene_bounds(s, mn, mx);
    double ctr[3], r = 0.0;
    for (int a = 0; a < 3; a++) {
        ctr[a] = 0.5 * ((double)mn[a] + mx[a]);
        r += 0.25 * ((double)mx[a] - mn[a]) * ((double)mx[a] - mn[a]);
    }
    r = sqrt(r);
    if (!(r > 0.0))
        r = 1.0;
    lanes_camera *k = &s->camera;
    double dist = r / sin(0.5 * k->fov_y_degrees * 3.14159265358979323846 / 180.0) * 1.05;
    double dir[3] = {0.0, 0.35, 1.0}, l = sqrt(dir[1] * dir[1] + 1.0);
    for (int a = 0; a < 3; a++) {
        k->target[a] = (float)ctr[a];
        k->eye[a] = (float)(ctr[a] + dist * dir[a] / l);
    }
    k->up[0] = k->up[2] = 0.0f;
    k->up[1] = 1.0f;
}

lanes_status lanes_scene_validate(const lanes_scene *scene, lanes_error *err)
{
    const char *name = scene->name[0] ? scene->name : "scene";
    if (scene->triangle_count == 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: no triangles", name);
    }
    if (scene->triangle_count > LANES_SCENE_MAX_TRIANGLES) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: %zu triangles exceed the limit", name,
                               scene->triangle_count);
    }
    for (size_t i = 0; i < scene->material_count; i++) {
        const lanes_material *m = &scene->materials[i];
        if (memchr(m->name, '\0', sizeof m->name) == NULL) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: material %zu: name not terminated", name,
                                   i);
        }
        const char *problem = material_problem(m);
        if (problem) return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: material '%s' has %s", name, m->name, problem);
    }
    for (size_t i = 0; i < scene->triangle_count; i++) {
        if (scene->material_of[i] >= scene->material_count) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: triangle %zu has material %u of %zu", name,
                                   i, scene->material_of[i], scene->material_count);
        }
        const float *v = scene->verts + 9 * i;
        if (!finite3(v) || !finite3(v + 3) || !finite3(v + 6)) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: triangle %zu has a non-finite vertex", name,
                                   i);
        }
    }
    for (size_t i = 0; i < scene->point_light_count; i++) {
        const lanes_point_light *l = &scene->point_lights[i];
        if (!finite3(l->position) || !color_ok(l->intensity)) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                   "%s: point light %zu: non-finite position or invalid intensity", name, i);
        }
    }
    for (size_t i = 0; i < scene->area_light_count; i++) {
        const lanes_area_light *l = &scene->area_lights[i];
        if (!finite3(l->corner) || !finite3(l->edge_u) || !finite3(l->edge_v) ||
            !color_ok(l->emission)) {
            return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                   "%s: area light %zu: non-finite geometry or invalid emission", name, i);
        }
    }
    const lanes_camera *c = &scene->camera;
    double f[3], cr[3];
    for (int a = 0; a < 3; a++)
        f[a] = (double)c->target[a] - c->eye[a];
    cr[0] = f[1] * c->up[2] - f[2] * c->up[1];
    cr[1] = f[2] * c->up[0] - f[0] * c->up[2];
    cr[2] = f[0] * c->up[1] - f[1] * c->up[0];
    double fl = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    double ul = sqrt((double)c->up[0] * c->up[0] + (double)c->up[1] * c->up[1] +
                     (double)c->up[2] * c->up[2]);
    double cl = sqrt(cr[0] * cr[0] + cr[1] * cr[1] + cr[2] * cr[2]);
    if (!finite3(c->eye) || !finite3(c->target) || !finite3(c->up) || !(fl > 0.0) ||
        !(cl > 1e-6 * fl * ul)) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: camera: eye, target and up must be finite, eye != target, "
                               "and up not parallel to the view direction",
                               name);
    }
    if (!(c->fov_y_degrees > 0.0f && c->fov_y_degrees < 180.0f) || c->width <= 0 ||
        c->height <= 0) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: camera: fov must be in (0, 180) and the size positive", name);
    }
    return LANES_OK;
}

void lanes_mesh_free(lanes_mesh *mesh)
{
    if (!mesh)
        return;
    free(mesh->positions);
    free(mesh->indices);
    memset(mesh, 0, sizeof *mesh);
}

void lanes_xform_identity(lanes_xform *x)
{
    memset(x, 0, sizeof *x);
    x->m[0][0] = x->m[1][1] = x->m[2][2] = 1.0;
}

void lanes_xform_mul(lanes_xform *out, const lanes_xform *a, const lanes_xform *b)
{
    lanes_xform r;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 4; j++) {
            double s = j == 3 ? a->m[i][3] : 0.0;
            for (int k = 0; k < 3; k++)
                s += a->m[i][k] * b->m[k][j];
            r.m[i][j] = s;
        }
    }
    *out = r;
}

void lanes_xform_trs(lanes_xform *out, const double t[3], const lanes_xform *rotate,
                     const double s[3])
{
    lanes_xform r;
    if (rotate)
        r = *rotate;
    else
        lanes_xform_identity(&r);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++)
            r.m[i][j] *= s[j];
        r.m[i][3] = t[i];
    }
    *out = r;
}

void lanes_xform_rotation(lanes_xform *out, const double axis[3], double degrees)
{
    lanes_xform_identity(out);
    double len = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    if (!(len > 0.0))
        return;
    double x = axis[0] / len, y = axis[1] / len, z = axis[2] / len;
    double a = degrees * (3.14159265358979323846 / 180.0);
    double c = cos(a), s = sin(a), t = 1.0 - c;
    out->m[0][0] = t * x * x + c;
    out->m[0][1] = t * x * y - s * z;
    out->m[0][2] = t * x * z + s * y;
    out->m[1][0] = t * x * y + s * z;
    out->m[1][1] = t * y * y + c;
    out->m[1][2] = t * y * z - s * x;
    out->m[2][0] = t * x * z - s * y;
    out->m[2][1] = t * y * z + s * x;
    out->m[2][2] = t * z * z + c;
}

void lanes_xform_apply(const lanes_xform *x, const float in[3], float out[3])
{
    double p[3] = {in[0], in[1], in[2]};
    for (int i = 0; i < 3; i++)
        out[i] = (float)(x->m[i][0] * p[0] + x->m[i][1] * p[1] + x->m[i][2] * p[2] + x->m[i][3]);
}

lanes_status lanes_scene_add_mesh(lanes_scene *scene, const lanes_mesh *mesh, const lanes_xform *xf,
                                  uint32_t material, const char *what, lanes_error *err)
{
    lanes_status status;
    if (!what)
        what = "mesh";
    if (material >= scene->material_count) {
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "%s: material index %u does not exist (%zu materials)", what, material,
                               scene->material_count);
    }
    lanes_error sub;
    if (lanes_scene_reserve_triangles(scene, mesh->triangle_count, &sub) != LANES_OK) {
        return lanes_error_set(err, sub.status, "%s: %s", what, sub.message);
    }
    /* Transform each vertex once, not once per triangle using it. */
    float *tv = NULL;
    if (mesh->vertex_count > 0) {
        if (mesh->vertex_count > SIZE_MAX / (3 * sizeof(float)) ||
            !(tv = malloc(mesh->vertex_count * 3 * sizeof(float)))) {
            return lanes_error_set(err, LANES_ERR_OUT_OF_MEMORY, "%s: out of memory for %zu vertices", what,
                                   mesh->vertex_count);
        }
    }
    for (size_t v = 0; v < mesh->vertex_count; v++) {
        float *o = tv + 3 * v;
        if (xf)
            lanes_xform_apply(xf, mesh->positions + 3 * v, o);
        else
            memcpy(o, mesh->positions + 3 * v, 3 * sizeof(float));
        if (!finite3(o)) {
            status = lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: vertex %zu is not finite%s", what, v,
                                     finite3(mesh->positions + 3 * v) ? " after the transform" : "");
            free(tv);
            return status;
        }
        if (!within_bound(o)) {
            status = lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                     "%s: vertex %zu lies at (%g, %g, %g)%s, beyond the %g a scene's coordinates "
                                     "may reach (the renderer squares distances in float)",
                                     what, v, o[0], o[1], o[2], xf ? " after the transform" : "",
                                     (double)LANES_SCENE_MAX_COORD);
            free(tv);
            return status;
        }
    }
    float *dst = scene->verts + 9 * scene->triangle_count;
    uint32_t *mdst = scene->material_of + scene->triangle_count;
    for (size_t t = 0; t < mesh->triangle_count; t++) {
        for (int k = 0; k < 3; k++) {
            uint32_t i = mesh->indices[3 * t + k];
            if (i >= mesh->vertex_count) {
                status =
                    lanes_error_set(err, LANES_ERR_BAD_INPUT, "%s: triangle %zu refers to vertex %u of %zu",
                                    what, t, i, mesh->vertex_count);
                free(tv);
                return status;
            }
            memcpy(dst + 9 * t + 3 * k, tv + 3 * (size_t)i, 3 * sizeof(float));
        }
        mdst[t] = material;
    }
    scene->triangle_count += mesh->triangle_count;
    free(tv);
    return LANES_OK;
}
