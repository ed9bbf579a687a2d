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

#include "build/accuracy.h"
#include "build/error.h"

/* The first four kinds are what every renderer draws. The last two are
 * the path tracer's (lanes paths); the Whitted renderers (lanes render)
 * draw them as lanes_material_whitted_kind says. */
typedef enum lanes_material_kind {
    LANES_MAT_DIFFUSE = 0,  /* Lambertian, color = albedo, optional emission */
    LANES_MAT_MIRROR,       /* perfect specular reflection, color = reflectance */
    LANES_MAT_GLASS,        /* refraction with index ior, plus Fresnel reflection; rough with a roughness */
    LANES_MAT_EMISSIVE,     /* emits `emission`, reflects nothing */
    LANES_MAT_CONDUCTOR,    /* GGX metal of roughness, Fresnel from f0 (color = f0) */
    LANES_MAT_PLASTIC       /* color under a GGX dielectric coat of roughness */
} lanes_material_kind;

#define LANES_MAT_KIND_COUNT 6

/* A solid texture replaces a diffuse or plastic material's color by a
 * blend of two colors as a function of position (no UVs exist). */
typedef enum lanes_material_texture {
    LANES_MAT_TEXTURE_NONE = 0,
    LANES_MAT_TEXTURE_CHECKER,
    LANES_MAT_TEXTURE_NOISE,
    LANES_MAT_TEXTURE_MARBLE,
    LANES_MAT_TEXTURE_WOOD
} lanes_material_texture;

typedef struct lanes_material {
    char name[64];
    lanes_material_kind kind;
    float color[3];     /* reflectance in [0, 1]; a texture's mean color with one */
    float ior;          /* glass only */
    float emission[3];  /* emissive, and optional on diffuse */
    float roughness;    /* conductor, plastic, glass (0: smooth): in [0, 1] */
    float f0[3];        /* conductor: reflectance at normal incidence, in [0, 1] */
    lanes_material_texture texture;
    float texture_scale;        /* > 0, the pattern's size in scene units */
    float texture_colors[2][3]; /* the blend's ends, in [0, 1] */
} lanes_material;

/* A rough glass's ior keeps this far from 1 (LANES_BSDF_MIN_IOR_GAP). */
#define LANES_MAT_MIN_IOR_GAP 1e-4f

/* The most materials a scene may have: the path tracer's stream sort counts
 * them in 16 bits. */
#define LANES_SCENE_MAX_MATERIALS 65536u

/* How the Whitted renderers draw a material: a conductor as a mirror
 * tinted by f0 (color), a plastic as its diffuse base. */
static inline lanes_material_kind lanes_material_whitted_kind(lanes_material_kind kind)
{
    return kind == LANES_MAT_CONDUCTOR ? LANES_MAT_MIRROR : kind == LANES_MAT_PLASTIC ? LANES_MAT_DIFFUSE : kind;
}

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

/* The largest image side the renderers take: a scene file's camera and
 * `lanes render --size` are checked against it when read. */
#define LANES_CAMERA_MAX_SIDE 16384

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
    /* The lanes_accuracy a scene file asks for ("accuracy"), or -1: the
     * renderer's choice. */
    int accuracy;
    /* Allocated lengths (in elements) of the arrays above, kept by the
     * append helpers below so appending is amortized O(1). A scene filled
     * by hand may leave them 0: the helpers then reallocate on the next
     * append, so the arrays must come from malloc. */
    size_t triangle_capacity;
    size_t material_capacity;
    size_t point_light_capacity;
    size_t area_light_capacity;
    /* The loaders' memory policy (lanes_scene_limit_to_memory, in
     * build/memory_limit.h): at most triangle_budget triangles, because
     * budget_note ("this machine has 23.4 GiB of memory"); an empty note:
     * no policy, only LANES_SCENE_MAX_TRIANGLES. The append path only
     * compares. */
    size_t triangle_budget;
    char budget_note[96];
} lanes_scene;

/* Triangle indices are uint32_t throughout (material_of, BVH prim_index), and
 * a scene this large would need 72 GiB of vertices anyway. */
#define LANES_SCENE_MAX_TRIANGLES ((size_t)1 << 31)

/* Memory per triangle, for refusing absurd sizes before the kernel's OOM
 * killer does (the loaders' budget, lanes_scene_limit_to_memory, counts
 * both, since a scene is loaded to be traced): a scene holds 9 floats and a
 * material index; building its acceleration structure peaks at about 272
 * bytes more (measured: `lanes render hairball --scheme wide`, 2.88M
 * triangles, 899 MB resident at most; the BVH2 alone, --scheme single,
 * peaks at 715 MB). */
#define LANES_SCENE_BYTES_PER_TRIANGLE ((size_t)(9 * 4 + 4))
#define LANES_ACCEL_BYTES_PER_TRIANGLE ((size_t)272)

/* The loaders keep |coordinate| <= LANES_SCENE_MAX_COORD, for what the
 * renderer computes from coordinates: a light's falloff squares a distance
 * of up to 2e18 * sqrt(3), 1.2e37, inside float's 3.4e38; past the bound
 * such products overflow to infinity (black surfaces, lights that vanish).
 * lanes_scene_add_mesh (every object of a scene file, every mesh file) and
 * the lights refuse coordinates beyond it with the object's name.
 * lanes_scene_add_triangle, the container's raw append, does not check:
 * the kernel tests feed it extreme coordinates on purpose, and the kernels
 * handle any finite ones. Precision is another limit, not checked here: an
 * object far from the origin (a unit sphere at 1e17) has coordinates float
 * cannot tell apart. */
#define LANES_SCENE_MAX_COORD 1e18f

/* An empty scene: no arrays, a camera at (0,0,5) looking at the origin, 45
 * degrees, 512x512 (the thesis' image size). */
void lanes_scene_init(lanes_scene *scene);

/* Frees the arrays and leaves the scene as lanes_scene_init does. Safe on a
 * zeroed or already freed scene. */
void lanes_scene_free(lanes_scene *scene);

/* Scene bounds over all triangle vertices. Non-finite coordinates are
 * skipped; with no finite vertex, min = +inf and max = -inf. */
void lanes_scene_bounds(const lanes_scene *scene, float min[3], float max[3]);

/* How far fast and default modes push secondary origins off their surface:
 * 1e-5 of the bounding-box diagonal, with no absolute term, so a scene
 * scaled by any factor renders the same (a fixed 1e-6 term displaced
 * shadows at scale 1e-6 and blackened everything at 1e-7). Whether the
 * offset also clears the rounding of coordinates far from the origin is
 * the scene plan's question (trace/scene_plan.h). 0 for a scene without a
 * finite vertex. The diagonal is summed in double: squaring a coordinate
 * difference of 1e18 in float would overflow. */
float lanes_scene_epsilon(const lanes_scene *scene);

/* Append helpers. They grow the arrays geometrically with overflow-checked
 * sizes, refuse more than LANES_SCENE_MAX_TRIANGLES triangles or the
 * scene's triangle_budget (checked at every count, not only when the arrays
 * grow: they grow by doubling), and on failure leave the scene unchanged
 * and return an error with a message (LANES_ERR_OUT_OF_MEMORY past the budget). */
lanes_status lanes_scene_reserve_triangles(lanes_scene *scene, size_t extra, lanes_error *err);
lanes_status lanes_scene_add_triangle(lanes_scene *scene, const float v[9], uint32_t material,
                                      lanes_error *err);
/* *index (may be NULL) receives the new material's index. Names must be
 * unique within a scene. */
lanes_status lanes_scene_add_material(lanes_scene *scene, const lanes_material *m, uint32_t *index,
                                      lanes_error *err);
lanes_status lanes_scene_add_point_light(lanes_scene *scene, const lanes_point_light *l, lanes_error *err);
lanes_status lanes_scene_add_area_light(lanes_scene *scene, const lanes_area_light *l, lanes_error *err);
/* Index of the material called `name`, or -1. */
long lanes_scene_find_material(const lanes_scene *scene, const char *name);

/* Points the camera (keeping its fov and size) at the center of the bounds
 * from +z and a little above, far enough for the bounding sphere to fit. */
void lanes_scene_frame_camera(lanes_scene *scene);

/* Checks what every consumer relies on: finite vertices, material indices
 * in range, finite non-negative colors, ior > 0 for glass, a usable camera
 * (finite, eye != target, up not parallel to the view, 0 < fov < 180,
 * positive size). */
lanes_status lanes_scene_validate(const lanes_scene *scene, lanes_error *err);

/* An indexed triangle mesh, as read from a file or generated, before it is
 * placed in a scene (the same mesh may be placed several times). */
typedef struct lanes_mesh {
    float *positions;  /* xyz per vertex */
    uint32_t *indices; /* three vertex indices per triangle, all < vertex_count */
    size_t vertex_count;
    size_t triangle_count;
} lanes_mesh;

void lanes_mesh_free(lanes_mesh *mesh);

/* A 3x4 affine transform, row-major: p' = M[0..2][0..2] p + M[0..2][3]. */
typedef struct lanes_xform {
    double m[3][4];
} lanes_xform;

void lanes_xform_identity(lanes_xform *x);
/* out = a * b (apply b first); out may alias a or b. */
void lanes_xform_mul(lanes_xform *out, const lanes_xform *a, const lanes_xform *b);
/* translate(t) * rotate * scale(s), the usual object placement. rotate may
 * be NULL (no rotation). */
void lanes_xform_trs(lanes_xform *out, const double t[3], const lanes_xform *rotate,
                     const double s[3]);
/* Rotation about a (not necessarily unit) axis, angle in degrees. */
void lanes_xform_rotation(lanes_xform *out, const double axis[3], double degrees);
/* out may alias in. */
void lanes_xform_apply(const lanes_xform *x, const float in[3], float out[3]);

/* Moves the whole scene by a uniform scale about the origin, then a
 * translation by t on every axis (p' = s p + (t, t, t), computed in double
 * and rounded once): triangles, lights and camera alike, so the image is
 * the same scene seen from the same place (point lights' intensities are
 * multiplied by s^2, which keeps the irradiance they give). Fails, leaving the scene
 * unchanged, when s is not finite and positive, t is not finite, or a
 * coordinate would leave LANES_SCENE_MAX_COORD. */
lanes_status lanes_scene_scale_translate(lanes_scene *scene, double s, double t, lanes_error *err);

/* Appends the mesh's triangles, transformed by xf (NULL: identity), all with
 * material `material` (which must exist). Fails on non-finite transformed
 * vertices or out-of-range indices, naming `what` (e.g. the file) in the
 * message; the scene is then unchanged. */
lanes_status lanes_scene_add_mesh(lanes_scene *scene, const lanes_mesh *mesh, const lanes_xform *xf,
                                  uint32_t material, const char *what, lanes_error *err);

#endif
