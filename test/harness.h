/*
 * harness.h
 *		Minimal test harness for the core suite: every CHECK counts one pass or
 *		one failure; main() prints "N passed, N failed".
 */
#ifndef TDC_HARNESS_H
#define TDC_HARNESS_H

#include <stdio.h>
#include <time.h>

extern long tdc_test_passed;
extern long tdc_test_failed;

#define CHECK(cond, ...) \
	do { \
		if (cond) \
			tdc_test_passed++; \
		else \
		{ \
			tdc_test_failed++; \
			fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__); \
			fprintf(stderr, __VA_ARGS__); \
			fputc('\n', stderr); \
		} \
	} while (0)

/* Seconds on the monotonic clock, for the checks that time something. */
static inline double
tdc_test_now(void)
{
	struct timespec ts;

	clock_gettime(CLOCK_MONOTONIC, &ts);
	return ts.tv_sec + ts.tv_nsec * 1e-9;
}

/* Each test file exports one entry point, called from test_main.c. */
extern void test_predicates(void);
extern void test_engine(void);
extern void test_conformance(void);
extern void test_memory(void);
extern void test_cache(void);
extern void test_concurrency(void);
extern void test_tolerance(void);
extern void test_voronoi(void);
extern void test_tile(void);
extern void test_tile_plan(void);
extern void test_bounded(void);
extern void test_bounded_labels(void);
extern void test_raster_tiles(void);
extern void test_contour_tiles(void);
extern void test_cdt(void);
extern void test_tin(void);
extern void test_tin_reference(void);
extern void test_tin_maxedge(void);

/* Set by --quick (sanitizer runs): smaller sizes. */
extern int	tdc_test_quick;

#endif
