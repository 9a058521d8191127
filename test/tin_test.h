/*
 * tin_test.h
 *		The helpers of test_tin.c that test_tin_maxedge.c uses too: a TIN
 *		over points with heights, a method parsed, an operation waited for,
 *		a value at a point, a level's length summed over the triangles.
 */
#ifndef TDC_TIN_TEST_H
#define TDC_TIN_TEST_H

#include "tdc.h"

typedef struct tin_case
{
	tdc_job    *job;
	tdc_tin    *tin;
} tin_case;

/* triangulate xy and build the TIN of heights z on "threads" threads (a CHECK fails otherwise) */
extern bool mk(tin_case *c, const double *xy, const double *z, size_t n, int threads);
extern void rm(tin_case *c);
/* the method's text parsed (a CHECK fails on an error) */
extern tdc_interp_spec spec_of(const char *text);
/* wait for the operation whose start returned rc (a CHECK fails on an error) */
extern int	run_wait(tdc_tin *tin, int rc, const char *what);
/* the method's value at (x, y); *valid (may be NULL): tdc_tin_value's result */
extern double value(tdc_tin *tin, const char *method, double x, double y, int *valid);
/*
 * The total length of level L's level set over the triangles, each
 * computed on its own in long double; max_edge > 0 leaves out the
 * triangles with a longer edge (compared in double: exact on the small
 * dyadic coordinates the tests give it).
 */
extern double level_length(const tdc_job *job, const double *z, double L, double max_edge);

#endif
