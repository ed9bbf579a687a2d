/* The render plan of a scene (see scene_plan.h). */
#include "trace/scene_plan.h"

#include <float.h>
#include <math.h>
#include <string.h>

void lanes_scene_plan_make(const lanes_scene *scene, int requested, lanes_scene_plan *plan)
{
    memset(plan, 0, sizeof *plan);
    for (size_t i = 0; i < scene->triangle_count; i++) {
        lanes_material_kind kind = lanes_material_whitted_kind(scene->materials[scene->material_of[i]].kind);
        if ((int)kind >= 0 && kind < 4) plan->triangles_of_kind[kind]++;
    }
    plan->point_lights = scene->point_light_count;
    plan->area_lights = scene->area_light_count;
    bool lights = plan->point_lights + plan->area_lights > 0;
    plan->shadow_rays = lights && plan->triangles_of_kind[LANES_MAT_DIFFUSE] > 0;
    plan->refraction = plan->triangles_of_kind[LANES_MAT_GLASS] > 0;
    plan->specular_pass = plan->refraction || plan->triangles_of_kind[LANES_MAT_MIRROR] > 0;
    plan->hit_geometry = plan->shadow_rays || plan->specular_pass;

    float lo[3], hi[3];
    lanes_scene_bounds(scene, lo, hi);
    double diag2 = 0.0, reach2 = 0.0, extent = 0.0;
    plan->has_vertices = true;
    for (int a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) { /* no finite vertex */
            plan->has_vertices = false;
            break;
        }
        double l = lo[a], h = hi[a], e = scene->camera.eye[a];
        diag2 += (h - l) * (h - l);
        reach2 += (fmax(h, e) - fmin(l, e)) * (fmax(h, e) - fmin(l, e));
        extent = fmax(extent, fmax(fabs(l), fabs(h)));
    }
    double edge2 = 0.0;
    for (size_t t = 0; plan->has_vertices && t < scene->triangle_count; t++) {
        const float *v = scene->verts + 9 * t;
        for (int k = 0; k < 3; k++) {
            const float *p = v + 3 * k, *q = v + 3 * ((k + 1) % 3);
            double dx = (double)q[0] - p[0], dy = (double)q[1] - p[1], dz = (double)q[2] - p[2];
            double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 > edge2) edge2 = d2; /* a NaN (non-finite vertex) is skipped */
        }
    }
    plan->extent = plan->has_vertices ? extent : 0.0;
    plan->diagonal = plan->has_vertices ? sqrt(diag2) : 0.0;
    plan->reach = plan->has_vertices ? sqrt(reach2) : 0.0;
    plan->longest_edge = sqrt(edge2);
    plan->epsilon = lanes_scene_epsilon(scene);
    int e;
    frexp(plan->extent > 0.0 ? plan->extent : 1.0, &e);
    double ulp = ldexp(1.0, e - 24); /* spacing of floats just below 2^e */
    plan->epsilon_ulps = plan->epsilon / ulp;
    const double u = 0x1p-24, gamma3 = 3.0 * u / (1.0 - 3.0 * u);
    double perr = u * plan->extent + gamma3 * plan->longest_edge; /* per coordinate */
    plan->offset_bound = 2.0 * sqrt(3.0) * perr + sqrt(3.0) * ulp;
    plan->recommend_robust = plan->epsilon < plan->offset_bound;

    if (requested >= 0 && requested < LANES_ACCURACY_COUNT) {
        plan->accuracy = (lanes_accuracy)requested;
        plan->accuracy_from = "--accuracy";
    } else if (scene->accuracy >= 0 && scene->accuracy < LANES_ACCURACY_COUNT) {
        plan->accuracy = (lanes_accuracy)scene->accuracy;
        plan->accuracy_from = "the scene file";
    } else {
        plan->accuracy = LANES_ACCURACY_DEFAULT;
        plan->accuracy_from = "the default";
    }
}

static const char *on(bool b) { return b ? "on " : "off"; }

void lanes_scene_plan_explain(const lanes_scene_plan *p, FILE *out)
{
    const size_t *k = p->triangles_of_kind;
    fprintf(out, "scene: %zu diffuse, %zu mirror, %zu glass, %zu emissive triangles; "
                 "%zu point and %zu area lights\n",
            k[LANES_MAT_DIFFUSE], k[LANES_MAT_MIRROR], k[LANES_MAT_GLASS], k[LANES_MAT_EMISSIVE],
            p->point_lights, p->area_lights);
    fprintf(out, "  shadow rays      %s  %s\n", on(p->shadow_rays),
            p->shadow_rays ? "lights shine on diffuse surfaces"
            : p->point_lights + p->area_lights == 0 ? "no lights: diffuse surfaces get ambient light only"
                                                   : "no diffuse surface receives light");
    fprintf(out, "  specular pass    %s  %s\n", on(p->specular_pass),
            p->specular_pass ? "mirror or glass materials reflect rays"
                             : "no mirror or glass: no reflected rays, no specular queues to set up");
    fprintf(out, "  refraction       %s  %s\n", on(p->refraction),
            p->refraction ? "glass materials refract rays" : "no glass material");
    fprintf(out, "  hit geometry     %s  %s\n", on(p->hit_geometry),
            p->hit_geometry
                ? "barycentrics and geometric normals are read: shadow and specular rays leave "
                  "surfaces from the hit point"
                : "no ray leaves a surface: hits are shaded by their material alone, without "
                  "barycentrics or normals");
    fprintf(out, "  accuracy         %s (from %s)\n", lanes_accuracy_name(p->accuracy), p->accuracy_from);
    fprintf(out, "    coordinates reach %.6g, bounding-box diagonal %.6g, longest edge %.6g: the "
                 "fast/default offset %.3g is %.3g ulps of the largest coordinate; robust mode's "
                 "error bound moves a hit point up to %.3g\n",
            p->extent, p->diagonal, p->longest_edge, p->epsilon, p->epsilon_ulps, p->offset_bound);
    lanes_error err;
    if (lanes_scene_plan_check(p, &err) != LANES_OK)
        fprintf(out, "    refused: %s\n", err.message);
    else if (p->recommend_robust && p->accuracy != LANES_ACCURACY_ROBUST)
        fprintf(out, "    recommended: --accuracy robust. The fixed offset is below that bound, so "
                     "secondary rays can hit the surface they leave; robust offsets scale with the "
                     "coordinates instead\n");
    else if (p->recommend_robust)
        fprintf(out, "    robust, as recommended: the fixed offset would be below that bound\n");
    else
        fprintf(out, "    the fixed offset exceeds that bound: fast and default modes are safe "
                     "from self-intersection here\n");
}

lanes_status lanes_scene_plan_check(const lanes_scene_plan *p, lanes_error *err)
{
    if (!p->has_vertices) return LANES_OK;
    const char *mode = lanes_accuracy_name(p->accuracy);
    const bool robust = p->accuracy == LANES_ACCURACY_ROBUST;
    const double min_diagonal = lanes_accuracy_min_diagonal(p->accuracy);
    if (p->diagonal < min_diagonal) {
        if (robust)
            return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                   "the scene's diagonal %.3g is below the %.0e robust mode can trace "
                                   "(its triangle test multiplies two distances: float underflows)",
                                   p->diagonal, min_diagonal);
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "the scene's diagonal %.3g is below the %.0e %s mode can trace (its "
                               "triangle test multiplies a distance and two edges: float underflows); "
                               "robust mode traces it down to %.0e",
                               p->diagonal, min_diagonal, mode,
                               lanes_accuracy_min_diagonal(LANES_ACCURACY_ROBUST));
    }
    const double max_reach = lanes_accuracy_max_reach(p->accuracy, p->longest_edge);
    if (p->reach > max_reach) {
        if (robust)
            return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                                   "the scene with its camera spans %.3g, beyond the %.0e robust mode "
                                   "can trace (its triangle test multiplies two distances: float "
                                   "overflows)",
                                   p->reach, max_reach);
        return lanes_error_set(err, LANES_ERR_BAD_INPUT,
                               "the scene is too large for %s mode: its triangle test multiplies a "
                               "distance (up to %.3g with the camera) and two edges (up to %.3g), "
                               "6 times which, %.3g, overflows float (%.3g); robust mode traces "
                               "distances up to %.0e",
                               mode, p->reach, p->longest_edge,
                               6.0 * p->reach * p->longest_edge * p->longest_edge, (double)FLT_MAX,
                               lanes_accuracy_max_reach(LANES_ACCURACY_ROBUST, p->longest_edge));
    }
    return LANES_OK;
}
