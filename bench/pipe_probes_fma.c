/* The FMA probes of pipe_probes.h: compiled with the avx2 set's flags. */
#include "bench/pipe_probes.h"

PIPE_PROBE(pipe_probe_fma, PIPE_PROBE_YMM_INIT,
           PIPE_PROBE_EACH("vfmadd231ps %%ymm12, %%ymm14, %%ymm\\r"), PIPE_PROBE_CLOBBERS)
/* half FMAs, half adds: whether the two share pipes */
PIPE_PROBE(pipe_probe_fma_add, PIPE_PROBE_YMM_INIT,
           ".irp r,0,2,4,6,8,10\n\t vfmadd231ps %%ymm12, %%ymm14, %%ymm\\r\n\t .endr\n\t"
           ".irp r,1,3,5,7,9,11\n\t vaddps %%ymm12, %%ymm\\r, %%ymm\\r\n\t .endr\n\t",
           PIPE_PROBE_CLOBBERS)
