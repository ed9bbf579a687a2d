/* The probes that pipe_rates.c times: loops of PIPE_PROBE_OPS independent
 * operations of one kind (12 chains, more than latency x pipes on any core
 * here, so only the pipes limit them), in assembly so that the compiler
 * can neither drop nor reorder them.
 *
 * Each instruction set's probes live in a file of their own, compiled with
 * that set's flags and checked at its level by the ISA hygiene tests, like
 * a kernel set: pipe_probes_avx.c, pipe_probes_fma.c (AVX2 and FMA),
 * pipe_probes_avx512.c. pipe_rates.c calls one only after lanes_cpu() says
 * the CPU has its instructions.
 *
 * Every probe takes n (loop iterations), a 64-byte aligned buffer of
 * PIPE_PROBE_OPS x 16 floats, and m: a 32-byte mask (lanes 0, 2, 4, 6
 * set) followed by 8 floats of 1.0. */
#ifndef LANES_BENCH_PIPE_PROBES_H
#define LANES_BENCH_PIPE_PROBES_H

#include <stdint.h>

enum { PIPE_PROBE_OPS = 12 };

typedef void (*pipe_probe_fn)(uint64_t n, float *buf, const int32_t *m);

/* AVX (pipe_probes_avx.c) */
void pipe_probe_mul(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_add(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_mul_add(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_logic(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_load(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_store(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_masked_store(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_merge(uint64_t n, float *buf, const int32_t *m);
/* AVX2 and FMA (pipe_probes_fma.c) */
void pipe_probe_fma(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_fma_add(uint64_t n, float *buf, const int32_t *m);
/* AVX-512F (pipe_probes_avx512.c) */
void pipe_probe_zmm_fma(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_zmm_load(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_zmm_store(uint64_t n, float *buf, const int32_t *m);
void pipe_probe_zmm_masked_store(uint64_t n, float *buf, const int32_t *m);

/* What the probe files share to write one. */
#define PIPE_PROBE_REGS "0,1,2,3,4,5,6,7,8,9,10,11"
#define PIPE_PROBE_CLOBBERS                                                                      \
    "cc", "memory", "xmm0", "xmm1", "xmm2", "xmm3", "xmm4", "xmm5", "xmm6", "xmm7", "xmm8", "xmm9", \
        "xmm10", "xmm11", "xmm12", "xmm13", "xmm14", "xmm15"

/* Zeroes the 12 destinations (zeros keep FP operations off slow denormal
 * paths), loads the mask into ymm13 and the ones into ymm14. */
#define PIPE_PROBE_YMM_INIT                                                                    \
    ".irp r," PIPE_PROBE_REGS "\n\t vxorps %%ymm\\r, %%ymm\\r, %%ymm\\r\n\t .endr\n\t"          \
    "vxorps %%ymm12, %%ymm12, %%ymm12\n\t"                                                      \
    "vmovups (%[m]), %%ymm13\n\t"                                                              \
    "vmovups 32(%[m]), %%ymm14\n\t"

/* A probe: init, then n times its body, then vzeroupper so that the
 * baseline code after it pays no AVX-SSE transition. */
#define PIPE_PROBE(name, init, body, ...)                                          \
    void name(uint64_t n, float *buf, const int32_t *m)                            \
    {                                                                              \
        __asm__ volatile(init "1:\n\t" body "dec %[n]\n\t"                         \
                              "jnz 1b\n\t"                                         \
                              "vzeroupper"                                         \
                         : [n] "+r"(n)                                             \
                         : [b] "r"(buf), [m] "r"(m)                                \
                         : __VA_ARGS__);                                           \
    }

/* insn once per destination register \r, 0 to 11 */
#define PIPE_PROBE_EACH(insn) ".irp r," PIPE_PROBE_REGS "\n\t " insn "\n\t .endr\n\t"

#endif
