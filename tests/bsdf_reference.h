/* The BSDFs of trace/bsdf.h in double precision, written from the
 * formulas rather than from trace/kernels/bsdf_core.h (GGX's D and G in
 * their tangent forms, the Fresnel terms directly), for tests/test_bsdf.c. */
#ifndef LANES_TESTS_BSDF_REFERENCE_H
#define LANES_TESTS_BSDF_REFERENCE_H

#include "trace/bsdf.h"

/* f(wo, wi) per channel and the pdf of bsdf_sample's directions; 0 for the
 * delta kinds. Directions unit length, in the shading frame. Rough glass's
 * transmission without the radiance scaling (eta_o / eta_i)^2, as the
 * library's: f(wo, wi) eta_o^2 = f(wi, wo) eta_i^2. */
void ref_bsdf_eval(const lanes_bsdf *b, const double wo[3], const double wi[3], double f[3], double *pdf);

/* Reflectance of a smooth dielectric, light from the side of index eta_i
 * at cos(theta) = ci onto eta_t (1 at and beyond the critical angle). */
double ref_dielectric_fresnel(double ci, double eta_i, double eta_t);

#endif
