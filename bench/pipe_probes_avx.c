/* The AVX probes of pipe_probes.h: compiled with the avx set's flags. */
#include "bench/pipe_probes.h"

PIPE_PROBE(pipe_probe_mul, PIPE_PROBE_YMM_INIT, PIPE_PROBE_EACH("vmulps %%ymm12, %%ymm\\r, %%ymm\\r"),
           PIPE_PROBE_CLOBBERS)
PIPE_PROBE(pipe_probe_add, PIPE_PROBE_YMM_INIT, PIPE_PROBE_EACH("vaddps %%ymm12, %%ymm\\r, %%ymm\\r"),
           PIPE_PROBE_CLOBBERS)
PIPE_PROBE(pipe_probe_mul_add, PIPE_PROBE_YMM_INIT,
           ".irp r,0,2,4,6,8,10\n\t vmulps %%ymm12, %%ymm\\r, %%ymm\\r\n\t .endr\n\t"
           ".irp r,1,3,5,7,9,11\n\t vaddps %%ymm12, %%ymm\\r, %%ymm\\r\n\t .endr\n\t",
           PIPE_PROBE_CLOBBERS)
PIPE_PROBE(pipe_probe_logic, PIPE_PROBE_YMM_INIT, PIPE_PROBE_EACH("vandps %%ymm13, %%ymm\\r, %%ymm\\r"),
           PIPE_PROBE_CLOBBERS)
PIPE_PROBE(pipe_probe_load, PIPE_PROBE_YMM_INIT, PIPE_PROBE_EACH("vmovups \\r*32(%[b]), %%ymm\\r"),
           PIPE_PROBE_CLOBBERS)
PIPE_PROBE(pipe_probe_store, PIPE_PROBE_YMM_INIT, PIPE_PROBE_EACH("vmovups %%ymm14, \\r*32(%[b])"),
           PIPE_PROBE_CLOBBERS)
PIPE_PROBE(pipe_probe_masked_store, PIPE_PROBE_YMM_INIT,
           PIPE_PROBE_EACH("vmaskmovps %%ymm14, %%ymm13, \\r*32(%[b])"), PIPE_PROBE_CLOBBERS)
/* What a masked store becomes without vmaskmovps: load, blend, store */
PIPE_PROBE(pipe_probe_merge, PIPE_PROBE_YMM_INIT,
           PIPE_PROBE_EACH("vmovups \\r*32(%[b]), %%ymm\\r\n\t vblendvps %%ymm13, %%ymm14, %%ymm\\r, "
                           "%%ymm\\r\n\t vmovups %%ymm\\r, \\r*32(%[b])"),
           PIPE_PROBE_CLOBBERS)
