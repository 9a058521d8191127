/*
 * test_main.c
 *		Runs the core suite: predicates, engine properties, conformance cases,
 *		concurrent use, the tolerance rule, constrained triangulations.
 *		Prints "N passed, N failed"; exits non-zero on any failure.
 *		--quick shrinks the largest inputs (sanitizer builds).
 */
#include <stdio.h>
#include <string.h>

#include "harness.h"

long		tdc_test_passed;
long		tdc_test_failed;
int			tdc_test_quick;

int
main(int argc, char **argv)
{
	for (int i = 1; i < argc; i++)
	{
		if (strcmp(argv[i], "--quick") == 0)
			tdc_test_quick = 1;
		/* one part alone, while working on it: --only tin, --only tile, --only bounded, --only raster */
		else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc && strcmp(argv[i + 1], "tin") == 0)
		{
			setvbuf(stdout, NULL, _IOLBF, 0);
			test_tin();
			test_tin_reference();
			printf("%ld passed, %ld failed\n", tdc_test_passed, tdc_test_failed);
			return tdc_test_failed ? 1 : 0;
		}
		else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc && strcmp(argv[i + 1], "bounded") == 0)
		{
			setvbuf(stdout, NULL, _IOLBF, 0);
			test_bounded();
			test_bounded_labels();
			test_raster_tiles();
			test_contour_tiles();
			printf("%ld passed, %ld failed\n", tdc_test_passed, tdc_test_failed);
			return tdc_test_failed ? 1 : 0;
		}
		else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc && strcmp(argv[i + 1], "raster") == 0)
		{
			setvbuf(stdout, NULL, _IOLBF, 0);
			test_raster_tiles();
			printf("%ld passed, %ld failed\n", tdc_test_passed, tdc_test_failed);
			return tdc_test_failed ? 1 : 0;
		}
		else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc && strcmp(argv[i + 1], "tile") == 0)
		{
			setvbuf(stdout, NULL, _IOLBF, 0);
			test_tile();
			printf("%ld passed, %ld failed\n", tdc_test_passed, tdc_test_failed);
			return tdc_test_failed ? 1 : 0;
		}
	}
	setvbuf(stdout, NULL, _IOLBF, 0);

	test_predicates();
	printf("predicates: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_engine();
	printf("engine: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_memory();
	printf("memory: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_cache();
	printf("cache: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_conformance();
	printf("conformance: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_concurrency();
	printf("concurrency: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_tolerance();
	printf("tolerance: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_voronoi();
	printf("voronoi: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_tile();
	printf("tile: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_bounded();
	test_bounded_labels();
	test_raster_tiles();
	test_contour_tiles();
	printf("bounded: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_cdt();
	printf("cdt: %ld passed, %ld failed so far\n", tdc_test_passed, tdc_test_failed);
	test_tin();
	test_tin_reference();
	printf("%ld passed, %ld failed\n", tdc_test_passed, tdc_test_failed);
	return tdc_test_failed ? 1 : 0;
}
