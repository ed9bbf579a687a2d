/* The render plan of a scene (see scene_plan.h). */
#include "trace/scene_plan.h"

#include <math.h>
#include <string.h>

#include "trace/shading.h"

void lanes_scene_plan_make(const lanes_scene *scene, int requested, lanes_scene_plan *plan)
{
    memset(plan, 0, sizeof *plan);
    for (size_t i = 0; i < scene->triangle_count; i++) {
        lanes_material_kind kind = scene->materials[scene->material_of[i]].kind;
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
    double diag2 = 0.0, extent = 0.0;
    for (int a = 0; a < 3; a++) {
        if (!(lo[a] <= hi[a])) continue; /* no finite vertex */
        diag2 += ((double)hi[a] - lo[a]) * ((double)hi[a] - lo[a]);
        extent = fmax(extent, fmax(fabs((double)lo[a]), fabs((double)hi[a])));
    }
    plan->extent = extent;
    plan->diagonal = sqrt(diag2);
    plan->epsilon = lanes_scene_epsilon(scene);
    int e;
    frexp(extent > 0.0 ? extent : 1.0, &e);
    double ulp = ldexp(1.0, e - 24); /* spacing of floats just below 2^e */
    plan->epsilon_ulps = plan->epsilon / ulp;
    plan->recommend_robust = plan->epsilon_ulps < LANES_PLAN_MIN_EPSILON_ULPS;

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
    fprintf(out, "    coordinates reach %.6g, bounding-box diagonal %.6g: the fast/default "
                 "offset %.3g is %.3g ulps of the largest coordinate\n",
            p->extent, p->diagonal, p->epsilon, p->epsilon_ulps);
    if (p->recommend_robust && p->accuracy != LANES_ACCURACY_ROBUST)
        fprintf(out, "    recommended: --accuracy robust. Below %.0f ulps the offset no longer "
                     "clears the rounding of hit points, so secondary rays can hit the surface "
                     "they leave; robust offsets scale with the coordinates instead\n",
                LANES_PLAN_MIN_EPSILON_ULPS);
    else if (p->recommend_robust)
        fprintf(out, "    robust, as recommended: the fixed offset would be below %.0f ulps\n",
                LANES_PLAN_MIN_EPSILON_ULPS);
    else
        fprintf(out, "    the fixed offset is at least %.0f ulps: fast and default modes are safe "
                     "from self-intersection here\n",
                LANES_PLAN_MIN_EPSILON_ULPS);
}
