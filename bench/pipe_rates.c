/* The core's execution resources, timed; see pipe_rates.h.
 *
 * Each probe is a loop of 12 independent operations of one kind (12 chains,
 * more than latency x pipes on any core here, so only the pipes limit
 * them), in assembly so that the compiler can neither drop nor reorder
 * them. Each runs only where the CPU has the instructions: its function
 * is compiled for them (target attribute) and called after lanes_cpu()
 * says so. */
#include "bench/pipe_rates.h"

#include <stdint.h>

#include "bench/cli_common.h"
#include "simd/isa.h"

enum { PROBE_OPS = 12 };

#define REGS12 "0,1,2,3,4,5,6,7,8,9,10,11"
#define YMM_CLOBBERS                                                                             \
    "cc", "memory", "xmm0", "xmm1", "xmm2", "xmm3", "xmm4", "xmm5", "xmm6", "xmm7", "xmm8", "xmm9", \
        "xmm10", "xmm11", "xmm12", "xmm13", "xmm14", "xmm15"

/* Zeroes the 12 destinations (zeros keep FP operations off slow denormal
 * paths), loads the mask (lanes 0, 2, 4, 6 set) into ymm13 and a value
 * into ymm14. */
#define YMM_INIT                                                                               \
    ".irp r," REGS12 "\n\t vxorps %%ymm\\r, %%ymm\\r, %%ymm\\r\n\t .endr\n\t"                   \
    "vxorps %%ymm12, %%ymm12, %%ymm12\n\t"                                                      \
    "vmovups (%[m]), %%ymm13\n\t"                                                              \
    "vmovups 32(%[m]), %%ymm14\n\t"

/* A probe: init, then n times its body, then vzeroupper so that the
 * baseline code after it pays no AVX-SSE transition. */
#define PROBE(name, isa, init, body, ...)                                                   \
    __attribute__((target(isa))) static void name(uint64_t n, float *buf, const int32_t *m) \
    {                                                                                          \
        __asm__ volatile(init "1:\n\t" body "dec %[n]\n\t"                                     \
                              "jnz 1b\n\t"                                                     \
                              "vzeroupper"                                                     \
                         : [n] "+r"(n)                                                         \
                         : [b] "r"(buf), [m] "r"(m)                                            \
                         : __VA_ARGS__);                                                       \
    }

#define EACH(insn) ".irp r," REGS12 "\n\t " insn "\n\t .endr\n\t"

PROBE(probe_fma, "avx2,fma", YMM_INIT, EACH("vfmadd231ps %%ymm12, %%ymm14, %%ymm\\r"), YMM_CLOBBERS)
PROBE(probe_mul, "avx", YMM_INIT, EACH("vmulps %%ymm12, %%ymm\\r, %%ymm\\r"), YMM_CLOBBERS)
PROBE(probe_add, "avx", YMM_INIT, EACH("vaddps %%ymm12, %%ymm\\r, %%ymm\\r"), YMM_CLOBBERS)
PROBE(probe_fma_add, "avx2,fma", YMM_INIT,
      ".irp r,0,2,4,6,8,10\n\t vfmadd231ps %%ymm12, %%ymm14, %%ymm\\r\n\t .endr\n\t"
      ".irp r,1,3,5,7,9,11\n\t vaddps %%ymm12, %%ymm\\r, %%ymm\\r\n\t .endr\n\t",
      YMM_CLOBBERS)
PROBE(probe_mul_add, "avx", YMM_INIT,
      ".irp r,0,2,4,6,8,10\n\t vmulps %%ymm12, %%ymm\\r, %%ymm\\r\n\t .endr\n\t"
      ".irp r,1,3,5,7,9,11\n\t vaddps %%ymm12, %%ymm\\r, %%ymm\\r\n\t .endr\n\t",
      YMM_CLOBBERS)
PROBE(probe_logic, "avx", YMM_INIT, EACH("vandps %%ymm13, %%ymm\\r, %%ymm\\r"), YMM_CLOBBERS)
PROBE(probe_load, "avx", YMM_INIT, EACH("vmovups \\r*32(%[b]), %%ymm\\r"), YMM_CLOBBERS)
PROBE(probe_store, "avx", YMM_INIT, EACH("vmovups %%ymm14, \\r*32(%[b])"), YMM_CLOBBERS)
PROBE(probe_masked_store, "avx", YMM_INIT, EACH("vmaskmovps %%ymm14, %%ymm13, \\r*32(%[b])"),
      YMM_CLOBBERS)
PROBE(probe_merge, "avx", YMM_INIT,
      EACH("vmovups \\r*32(%[b]), %%ymm\\r\n\t vblendvps %%ymm13, %%ymm14, %%ymm\\r, %%ymm\\r\n\t "
           "vmovups %%ymm\\r, \\r*32(%[b])"),
      YMM_CLOBBERS)

#define ZMM_INIT                                                                               \
    ".irp r," REGS12 "\n\t vpxord %%zmm\\r, %%zmm\\r, %%zmm\\r\n\t .endr\n\t"                   \
    "vpxord %%zmm12, %%zmm12, %%zmm12\n\t"                                                      \
    "vbroadcastss 32(%[m]), %%zmm13\n\t"                                                         \
    "vbroadcastss 32(%[m]), %%zmm14\n\t"                                                       \
    "movl $0x5555, %%eax\n\t"                                                                  \
    "kmovw %%eax, %%k1\n\t"
PROBE(probe_zmm_fma, "avx512f", ZMM_INIT, EACH("vfmadd231ps %%zmm12, %%zmm13, %%zmm\\r"),
      YMM_CLOBBERS, "eax", "k1")
PROBE(probe_zmm_load, "avx512f", ZMM_INIT, EACH("vmovups \\r*64(%[b]), %%zmm\\r"), YMM_CLOBBERS, "eax",
      "k1")
PROBE(probe_zmm_store, "avx512f", ZMM_INIT, EACH("vmovups %%zmm14, \\r*64(%[b])"), YMM_CLOBBERS, "eax",
      "k1")
PROBE(probe_zmm_masked_store, "avx512f", ZMM_INIT, EACH("vmovups %%zmm14, \\r*64(%[b])%{%%k1%}"),
      YMM_CLOBBERS, "eax", "k1")

typedef void (*probe_fn)(uint64_t n, float *buf, const int32_t *m);

/* The probe's loop iterations per second: grown until a run lasts a
 * quarter of run_ms, then the fastest of reps runs of about run_ms (being
 * preempted only ever makes a run slower). */
static double iterations_per_second(probe_fn fn, float *buf, const int32_t *m, int reps, double run_ms)
{
    uint64_t n = 64;
    double ns;
    for (;;) {
        uint64_t t0 = cli_now_ns();
        fn(n, buf, m);
        ns = (double)(cli_now_ns() - t0);
        if (ns > run_ms * 1e6 / 4 || n > ((uint64_t)1 << 40)) break;
        n *= 4;
    }
    n = (uint64_t)((double)n * run_ms * 1e6 / (ns > 1 ? ns : 1)) + 1;
    double best = 0;
    for (int r = 0; r < reps; r++) {
        uint64_t t0 = cli_now_ns();
        fn(n, buf, m);
        double t = (double)(cli_now_ns() - t0) * 1e-9;
        if (t > 0 && (double)n / t > best) best = (double)n / t;
    }
    return best;
}

static double per_cycle(probe_fn fn, float *buf, const int32_t *m, double hz, int reps, double run_ms)
{
    return iterations_per_second(fn, buf, m, reps, run_ms) * PROBE_OPS / hz;
}

km_pipes km_measure_pipes(double hz, int reps, double run_ms)
{
    km_pipes p = {0};
    const uint32_t cpu = lanes_cpu()->bits;
    if (!(cpu & LANES_CPU_AVX) || hz <= 0) return p;
    /* 12 destinations of 64 bytes; the mask (lanes 0, 2, 4, 6) then a value */
    static _Alignas(64) float buf[PROBE_OPS * 16];
    static _Alignas(64) const int32_t m[16] = {-1, 0, -1, 0, -1, 0, -1, 0, 0x3f800000, 0x3f800000,
                                               0x3f800000, 0x3f800000, 0x3f800000, 0x3f800000,
                                               0x3f800000, 0x3f800000};
    const bool fma = (cpu & LANES_CPU_FMA) && (cpu & LANES_CPU_AVX2);
    p.measured = true;
    p.mul = per_cycle(fma ? probe_fma : probe_mul, buf, m, hz, reps, run_ms);
    p.add = per_cycle(probe_add, buf, m, hz, reps, run_ms);
    p.mul_add = per_cycle(fma ? probe_fma_add : probe_mul_add, buf, m, hz, reps, run_ms);
    p.any = per_cycle(probe_logic, buf, m, hz, reps, run_ms);
    p.load = per_cycle(probe_load, buf, m, hz, reps, run_ms);
    p.store = per_cycle(probe_store, buf, m, hz, reps, run_ms);
    p.masked_store_cyc = 1.0 / per_cycle(probe_masked_store, buf, m, hz, reps, run_ms);
    p.merge_cyc = 1.0 / per_cycle(probe_merge, buf, m, hz, reps, run_ms);
    if (cpu & LANES_CPU_AVX512F) {
        p.zmm_mul = per_cycle(probe_zmm_fma, buf, m, hz, reps, run_ms);
        p.zmm_load = per_cycle(probe_zmm_load, buf, m, hz, reps, run_ms);
        p.zmm_store = per_cycle(probe_zmm_store, buf, m, hz, reps, run_ms);
        p.zmm_masked_store_cyc = 1.0 / per_cycle(probe_zmm_masked_store, buf, m, hz, reps, run_ms);
    }
    return p;
}
