/* The execution resources of the core this runs on, measured: how many
 * operations of each kind it completes per cycle when nothing else limits
 * them (independent operations on registers, or on an L1-resident
 * buffer). They feed the resource bound of `lanes bench kernels`
 * (kernel_model.h): a kernel's cycles per iteration can be no fewer than
 * its operations of a kind over that kind's rate, whichever kind is
 * scarcest. Measured rather than tabled, so a core the table never saw
 * (and a VM that hides what it is) is modelled as it runs.
 *
 * Every rate is of 256-bit (ymm) operations, which issue like 128-bit ones
 * on every core with AVX2 (Zen 2 on, Haswell on); the 512-bit rate is
 * measured apart, since cores differ there (Zen 4 splits a zmm operation
 * over two 256-bit pipe slots). */
#ifndef LANES_BENCH_PIPE_RATES_H
#define LANES_BENCH_PIPE_RATES_H

#include <stdbool.h>

typedef struct km_pipes {
    bool measured;           /* false: the CPU lacks AVX, nothing was timed */
    double mul;              /* vfmadd231ps (vmulps without FMA) per cycle */
    double add;              /* vaddps per cycle */
    double mul_add;          /* a half-and-half mix of the two: whether they share pipes */
    double any;              /* vandps per cycle: every pipe that takes vector logic */
    double load;             /* vmovups loads per cycle */
    double store;            /* vmovups stores per cycle */
    double masked_store_cyc; /* cycles per vmaskmovps store (half its lanes set) */
    double merge_cyc;        /* cycles per load + vblendvps + store of the same bytes */
    double zmm_mul;          /* vfmadd231ps on zmm per cycle; 0 without AVX-512 */
    double zmm_load;         /* vmovups zmm loads per cycle; 0 without AVX-512 */
    double zmm_store;        /* vmovups zmm stores per cycle; 0 without AVX-512 */
    double zmm_masked_store_cyc; /* cycles per opmask store of a zmm; 0 without AVX-512 */
} km_pipes;

/* Times each kind at clock hz (km_measure_clock_hz), the fastest of reps
 * runs of about run_ms each; only the kinds this CPU can execute. */
km_pipes km_measure_pipes(double hz, int reps, double run_ms);

#endif
