/*
 * tiles_test.h
 *		The helpers of test_raster_tiles.c that test_contour_tiles.c uses too:
 *		a uniform double, a case's points and heights staged as a bounded
 *		run's input files, and the files a run left beside them.
 */
#ifndef TDC_TILES_TEST_H
#define TDC_TILES_TEST_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* uniform in [0, 1), from the splitmix64 state s */
extern double tiles_u01(uint64_t *s);
/* n x,y pairs and n heights as dir/input.xy and dir/input.z */
extern bool tiles_stage(const char *dir, const double *xy, const double *z, size_t n);
/* the files in dir other than the staged input (-1: no directory) */
extern int	tiles_files_in(const char *dir);

#endif							/* TDC_TILES_TEST_H */
