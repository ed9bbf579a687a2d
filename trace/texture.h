/* Solid procedural textures: a surface's albedo as a function of the hit
 * point's position (lanes' meshes carry no UVs). Plain C parameters, shared
 * by the baseline code that fills them and the per-set shaders
 * (trace/kernels/texture_core.h) that evaluate them; each texture blends
 * color_a (at 0) into color_b (at 1). */
#ifndef LANES_TRACE_TEXTURE_H
#define LANES_TRACE_TEXTURE_H

typedef enum lanes_texture_kind {
    LANES_TEXTURE_CHECKER = 0, /* cubes of side `scale`, alternating */
    LANES_TEXTURE_NOISE,       /* gradient noise of feature size `scale`, mapped to [0, 1] */
    LANES_TEXTURE_MARBLE,      /* sine bands along x, bent by turbulence */
    LANES_TEXTURE_WOOD         /* rings around the y axis, bent by noise */
} lanes_texture_kind;

typedef struct lanes_texture {
    lanes_texture_kind kind;
    float scale; /* > 0: the pattern's size in scene units */
    float color_a[3], color_b[3];
} lanes_texture;

#endif
