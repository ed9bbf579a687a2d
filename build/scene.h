/* A scene as the tracer sees it: world-space triangles with a material
 * each, point and area lights, and a camera. Meshes from files and
 * generators are flattened into this one list at load time (no instancing):
 * the BVH builder and every traversal read the same flat triangles.
 *
 * Compiled for the x86-64 baseline. */
#ifndef LANES_BUILD_SCENE_H
#define LANES_BUILD_SCENE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

typedef enum lanes_material_kind {
    LANES_MAT_DIFFUSE = 0,  /* Lambertian, color = albedo */
    LANES_MAT_MIRROR,       /* perfect specular reflection, color = reflectance */
    LANES_MAT_GLASS,        /* refraction with index ior, plus Fresnel reflection */
    LANES_MAT_EMISSIVE      /* emits `emission`, reflects nothing */
} lanes_material_kind;

typedef struct lanes_material {
    char name[64];
    lanes_material_kind kind;
    float color[3];
    float ior;          /* glass only */
    float emission[3];  /* emissive only */
} lanes_material;

typedef struct lanes_point_light {
    float position[3];
    float intensity[3]; /* radiant intensity: irradiance falls off as 1/r^2 */
} lanes_point_light;

/* A parallelogram corner + s*edge_u + t*edge_v, s, t in [0,1], emitting on
 * the side of edge_u x edge_v. */
typedef struct lanes_area_light {
    float corner[3], edge_u[3], edge_v[3];
    float emission[3];
} lanes_area_light;

typedef struct lanes_camera {
    float eye[3], target[3], up[3];
    float fov_y_degrees;
    int width, height;  /* default image size; the CLI may override */
} lanes_camera;

typedef struct lanes_scene {
    char name[128];
    /* Triangle i has vertices verts[9i .. 9i+8] (v0, v1, v2; xyz each) and
     * material material_of[i]. */
    float *verts;
    uint32_t *material_of;
    size_t triangle_count;
    lanes_material *materials;
    size_t material_count;
    lanes_point_light *point_lights;
    size_t point_light_count;
    lanes_area_light *area_lights;
    size_t area_light_count;
    lanes_camera camera;
} lanes_scene;

/* Errors from loaders: which file, which line (0: none), what is wrong. */
typedef struct lanes_error {
    char message[512];
} lanes_error;

void lanes_scene_free(lanes_scene *scene);

/* Scene bounds over all triangle vertices. */
void lanes_scene_bounds(const lanes_scene *scene, float min[3], float max[3]);

#endif
