/*
 * tdc_guc.c
 *		Module initialisation and the tdc_delaunay.* settings.
 *
 * The settings only fill in the core's tdc_options and a few limits of the
 * PostgreSQL layer; they are read at the start of each triangulation.
 *
 *	tdc_delaunay.threads		worker threads per triangulation, 0 = one per
 *								online CPU (default 0)
 *	tdc_delaunay.max_threads	superuser-only ceiling on the above, 0 = the
 *								number of online CPUs (default 0)
 *	tdc_delaunay.grid_size		s of the s x s subdivision grid, 0 = automatic
 *	tdc_delaunay.levels			subdivision depth d, 0 = automatic, -1 = none
 *	tdc_delaunay.max_memory		MB one triangulation (input buffer, engine,
 *								result) may use, 0 = unlimited (default)
 *	tdc_delaunay.stats			NOTICE with counts, DETAIL with timings
 *	tdc_delaunay.max_result_bytes  test-only, superuser: lowers the 1 GB
 *								limit of a single result value so that the
 *								"use ST_TDCDelaunayDump" error can be tested
 *
 * Threads are real threads inside the backend, and every backend's threads
 * count against the server user's process limit: so by default no session
 * may use more threads than there are CPUs, and only a superuser can raise
 * (or, on a busy server, lower) that ceiling with tdc_delaunay.max_threads.
 */
#include "postgres.h"

#include <limits.h>

#include "fmgr.h"
#include "utils/guc.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

PG_MODULE_MAGIC;

int			tdc_guc_threads = 0;
int			tdc_guc_max_threads = 0;
int			tdc_guc_grid_size = 0;
int			tdc_guc_levels = 0;
int			tdc_guc_max_memory_mb = 0;
bool		tdc_guc_stats = false;
int			tdc_guc_max_result_bytes = (int) MaxAllocSize;

uint64
tdc_max_memory_bytes(void)
{
	return (uint64) tdc_guc_max_memory_mb * 1024 * 1024;
}

void		_PG_init(void);

void
_PG_init(void)
{
	DefineCustomIntVariable("tdc_delaunay.threads",
							"Worker threads per triangulation (0 = one per online CPU).",
							"Capped by tdc_delaunay.max_threads.",
							&tdc_guc_threads,
							0, 0, 1024,
							PGC_USERSET, 0,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.max_threads",
							"Ceiling on worker threads per triangulation (0 = the number of online CPUs).",
							NULL,
							&tdc_guc_max_threads,
							0, 0, 1024,
							PGC_SUSET, 0,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.grid_size",
							"Size s of the s x s grid used to subdivide the points (0 = automatic).",
							NULL,
							&tdc_guc_grid_size,
							0, 0, 1 << 16,
							PGC_USERSET, 0,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.levels",
							"Subdivision depth d, up to 2^d subsets (0 = automatic, -1 = no subdivision).",
							NULL,
							&tdc_guc_levels,
							0, -1, 30,
							PGC_USERSET, 0,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.max_memory",
							"Memory one triangulation may use (0 = unlimited).",
							"Counts the collected vertices, the engine's estimate and the result.",
							&tdc_guc_max_memory_mb,
							0, 0, INT_MAX,
							PGC_USERSET, GUC_UNIT_MB,
							NULL, NULL, NULL);

	DefineCustomBoolVariable("tdc_delaunay.stats",
							 "Report counts and phase timings of each triangulation as a NOTICE.",
							 NULL,
							 &tdc_guc_stats,
							 false,
							 PGC_USERSET, 0,
							 NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.max_result_bytes",
							"Test only: largest single result value in bytes.",
							"Only for testing the error raised for results over 1 GB; leave at the default.",
							&tdc_guc_max_result_bytes,
							(int) MaxAllocSize, 64, (int) MaxAllocSize,
							PGC_SUSET, GUC_NOT_IN_SAMPLE,
							NULL, NULL, NULL);

#if PG_VERSION_NUM >= 150000
	MarkGUCPrefixReserved("tdc_delaunay");
#else
	EmitWarningsOnPlaceholders("tdc_delaunay");
#endif
}
