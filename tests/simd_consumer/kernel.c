/* A width-generic kernel of an outside project, written once with lanes'
 * SIMD layer and compiled once per kernel set by lanes_add_kernel_sets: it
 * counts the elements below a threshold and scales the rest, a full vector
 * at a time, the tail element by element. */
#include <lanes/simd/simd.h>
/* installed beside it, and compiled here with the consumer's flags */
#include <lanes/simd/vmath.h>
#include <lanes/simd/vrandom.h>

#include <stddef.h>

int LANES_FN(consumer_lanes)(void) { return LANES_W; }

size_t LANES_FN(consumer_count_below_and_scale)(float *x, size_t n, float threshold, float scale)
{
    const vfloat t = vf_set1(threshold), s = vf_set1(scale);
    size_t below = 0, i = 0;
    for (; i + LANES_W <= n; i += LANES_W) {
        vfloat v = vf_loadu(x + i);
        vmask m = vf_lt(v, t);
        below += (size_t)vm_popcount(m);
        vf_storeu(x + i, vf_select(m, v, vf_mul(v, s)));
    }
    for (; i < n; i++) {
        if (x[i] < threshold)
            below++;
        else
            x[i] *= scale;
    }
    return below;
}
