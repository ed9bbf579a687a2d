/* The one mapping from image pixels to camera rays, used by the renderers,
 * the studies, `lanes compare` and the tests: a pinhole at the camera's
 * eye, looking at its target, with its vertical field of view over the
 * image's height.
 *
 * Compiled for the x86-64 baseline: no intrinsics. */
#ifndef LANES_BUILD_CAMERA_H
#define LANES_BUILD_CAMERA_H

#include "build/scene.h"
#include "build/vec3.h"

/* A camera set up for one image size. */
typedef struct lanes_view {
    vec3 eye, fwd, right, up; /* fwd, right, up: an orthonormal frame */
    float tan_half;           /* tan(fov_y / 2) */
    float aspect;             /* width / height */
    int width, height;
} lanes_view;

static inline lanes_view lanes_view_make(const lanes_camera *c, int width, int height)
{
    lanes_view v;
    v.eye = v3_load(c->eye);
    v.fwd = v3_normalize(v3_sub(v3_load(c->target), v.eye));
    v.right = v3_normalize(v3_cross(v.fwd, v3_load(c->up)));
    v.up = v3_cross(v.right, v.fwd);
    v.tan_half = tanf(c->fov_y_degrees * LANES_PI / 360.0f);
    v.width = width;
    v.height = height;
    v.aspect = (float)width / (float)height;
    return v;
}

/* The direction through image position (x, y), in pixels from the top-left
 * corner (a pixel's centre is x + 0.5, y + 0.5), not normalised: the
 * renderers trace it as it is, and v3_normalize makes it a unit vector. */
static inline vec3 lanes_view_dir(const lanes_view *v, float x, float y)
{
    float px = (2.0f * x / (float)v->width - 1.0f) * v->tan_half * v->aspect;
    float py = (1.0f - 2.0f * y / (float)v->height) * v->tan_half;
    return v3_add(v->fwd, v3_add(v3_scale(v->right, px), v3_scale(v->up, py)));
}

#endif
