/* The 512-bit probes of pipe_probes.h: compiled with the avx512 set's
 * flags. k1 holds lanes 0, 2, 4, ... for the opmask store. */
#include "bench/pipe_probes.h"

#define ZMM_INIT                                                                             \
    ".irp r," PIPE_PROBE_REGS "\n\t vpxord %%zmm\\r, %%zmm\\r, %%zmm\\r\n\t .endr\n\t"        \
    "vpxord %%zmm12, %%zmm12, %%zmm12\n\t"                                                    \
    "vbroadcastss 32(%[m]), %%zmm13\n\t"                                                      \
    "vbroadcastss 32(%[m]), %%zmm14\n\t"                                                      \
    "movl $0x5555, %%eax\n\t"                                                                \
    "kmovw %%eax, %%k1\n\t"

PIPE_PROBE(pipe_probe_zmm_fma, ZMM_INIT, PIPE_PROBE_EACH("vfmadd231ps %%zmm12, %%zmm13, %%zmm\\r"),
           PIPE_PROBE_CLOBBERS, "eax", "k1")
PIPE_PROBE(pipe_probe_zmm_load, ZMM_INIT, PIPE_PROBE_EACH("vmovups \\r*64(%[b]), %%zmm\\r"),
           PIPE_PROBE_CLOBBERS, "eax", "k1")
PIPE_PROBE(pipe_probe_zmm_store, ZMM_INIT, PIPE_PROBE_EACH("vmovups %%zmm14, \\r*64(%[b])"),
           PIPE_PROBE_CLOBBERS, "eax", "k1")
PIPE_PROBE(pipe_probe_zmm_masked_store, ZMM_INIT,
           PIPE_PROBE_EACH("vmovups %%zmm14, \\r*64(%[b])%{%%k1%}"), PIPE_PROBE_CLOBBERS, "eax", "k1")
