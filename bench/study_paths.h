/* `lanes study --paths`: Afra et al. 2016's measurements of the path
 * tracer's methods (trace/paths.h) at every set this CPU runs. */
#ifndef LANES_BENCH_STUDY_PATHS_H
#define LANES_BENCH_STUDY_PATHS_H

#include <stdbool.h>

#include "simd/isa.h"

typedef struct paths_study_options {
    const char *out_dir;
    int width, height, spp, reps, threads;
    bool json;
    bool embree;            /* also trace the same paths with Embree (a lanes built with it) */
    const char *embree_isa; /* its set, for the tables */
} paths_study_options;

/* Measures the scenes named by specs at the given sets and writes
 * paths.csv, tables.md and the plots to o->out_dir; prints the tables (or
 * JSON). Exits with status 2 on bad input, as every command. */
int lanes_study_paths(const char *const *specs, int nspecs, const lanes_isa *sets, int nsets,
                      const paths_study_options *o);

#endif
