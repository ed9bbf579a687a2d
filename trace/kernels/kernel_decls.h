/* The suffixed entry points of one kernel set, generated from the rows of
 * trace/kernel_list.h: their prototypes, the table's initializer, and the
 * counting and non-counting instantiations of each body. Included only by
 * per-ISA files. */
#ifndef LANES_TRACE_KERNEL_DECLS_H
#define LANES_TRACE_KERNEL_DECLS_H

#include "simd/simd.h"
#include "trace/kernels.h"

#define LANES_UNPAREN(...) __VA_ARGS__

/* The name of an entry point. The wide-BVH kernels compiled again for a
 * wider node (wide_variant.h) carry the width in theirs,
 * lanes_trace_wide_w16_avx2, beside the set's lanes_trace_wide_avx2. */
#ifdef LANES_WIDE_TAG
#define LANES_KFN(name) LANES_FN(LANES_CAT(name, LANES_WIDE_TAG))
#else
#define LANES_KFN(name) LANES_FN(name)
#endif

_Static_assert(LANES_TRI_ALGO_COUNT == 2, "PER_ALGO rows instantiate _moller and _watertight");

/* Prototypes. */
#define LANES_KERNEL_PROTO(kind, ret, name, params, args) LANES_KERNEL_PROTO_##kind(ret, name, params)
#define LANES_KERNEL_PROTO_PLAIN(ret, name, params) ret LANES_KFN(lanes_##name) params;
#define LANES_KERNEL_PROTO_COUNTED(ret, name, params) ret LANES_KFN(lanes_##name) params;
#define LANES_KERNEL_PROTO_COUNTED_VOID(ret, name, params) ret LANES_KFN(lanes_##name) params;
#define LANES_KERNEL_PROTO_PER_ALGO(ret, name, params)                                      \
    ret LANES_KFN(lanes_##name##_moller) params;                                            \
    ret LANES_KFN(lanes_##name##_watertight) params;
LANES_KERNELS(LANES_KERNEL_PROTO)

/* The table's initializer (kernel_table.c). */
#define LANES_KERNEL_INIT(kind, ret, name, params, args) LANES_KERNEL_INIT_##kind(name)
#define LANES_KERNEL_INIT_PLAIN(name) .name = LANES_KFN(lanes_##name),
#define LANES_KERNEL_INIT_COUNTED(name) .name = LANES_KFN(lanes_##name),
#define LANES_KERNEL_INIT_COUNTED_VOID(name) .name = LANES_KFN(lanes_##name),
#define LANES_KERNEL_INIT_PER_ALGO(name)                                                    \
    .name = {[LANES_TRI_MOLLER] = LANES_KFN(lanes_##name##_moller),                         \
             [LANES_TRI_WATERTIGHT] = LANES_KFN(lanes_##name##_watertight)},

/* The entry points of a family, expanded at the end of its file
 * (LANES_KERNELS_BOX(LANES_KERNEL_ENTRY)): each body is instantiated with
 * the caller's stats and with NULL, which compiles the counting out. */
#define LANES_KERNEL_ENTRY(kind, ret, name, params, args) LANES_KERNEL_ENTRY_##kind(ret, name, params, args)
#define LANES_KERNEL_ENTRY_PLAIN(ret, name, params, args)
#define LANES_KERNEL_ENTRY_COUNTED(ret, name, params, args)                                 \
    ret LANES_KFN(lanes_##name) params                                                      \
    {                                                                                      \
        return stats ? name##_body(LANES_UNPAREN args, stats) : name##_body(LANES_UNPAREN args, NULL); \
    }
#define LANES_KERNEL_ENTRY_COUNTED_VOID(ret, name, params, args)                            \
    ret LANES_KFN(lanes_##name) params                                                      \
    {                                                                                      \
        if (stats)                                                                         \
            name##_body(LANES_UNPAREN args, stats);                                        \
        else                                                                               \
            name##_body(LANES_UNPAREN args, NULL);                                         \
    }
#define LANES_KERNEL_ENTRY_PER_ALGO(ret, name, params, args)                                \
    LANES_KERNEL_ENTRY_ALGO_(ret, name, moller, LANES_TRI_MOLLER, params, args)            \
    LANES_KERNEL_ENTRY_ALGO_(ret, name, watertight, LANES_TRI_WATERTIGHT, params, args)
#define LANES_KERNEL_ENTRY_ALGO_(ret, name, algo_name, ALGO, params, args)                  \
    ret LANES_KFN(lanes_##name##_##algo_name) params                                        \
    {                                                                                      \
        return stats ? name##_body(ALGO, LANES_UNPAREN args, stats)                        \
                     : name##_body(ALGO, LANES_UNPAREN args, NULL);                        \
    }

#endif
