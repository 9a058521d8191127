/*
 * settings.c
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
 *	tdc_delaunay.levels			subdivision depth d, 0 = automatic, -1 = none,
 *								at most the core's TDC_MAX_LEVELS
 *	tdc_delaunay.max_memory		MB one triangulation (input buffer, engine,
 *								result) may use, 0 = up to the ceiling (default)
 *	tdc_delaunay.memory_ceiling	superuser-only ceiling on the above, 0 = half
 *								of the machine's physical memory (default),
 *								-1 = none
 *	tdc_delaunay.keep_memory	MB of freed engine arrays a session keeps for
 *								its next triangulation (default 256, 0 = none)
 *	tdc_delaunay.keep_memory_time  how long it keeps them after its last
 *								triangulation (default 10 s; mem_cache.c)
 *	tdc_delaunay.stats			NOTICE with counts, DETAIL with timings
 *	tdc_delaunay.max_result_bytes  test-only, superuser: lowers the 1 GB
 *								limit of a single result value so that the
 *								"use ST_TDCDelaunayDump" error can be tested
 *
 * Threads are real threads inside the backend, and every backend's threads
 * count against the server user's process limit: so by default no session
 * may use more threads than there are CPUs, and only a superuser can raise
 * (or, on a busy server, lower) that ceiling with tdc_delaunay.max_threads.
 *
 * Memory is the same story with a worse ending: a backend that asks for more
 * than the machine has is killed by the kernel, and the postmaster then
 * restarts every session.  So no triangulation may plan past
 * tdc_delaunay.memory_ceiling, by default half of the physical memory (one
 * big triangulation plus shared buffers and everyone else fits), and users
 * may only lower their own limit with tdc_delaunay.max_memory.
 */
#include "postgres.h"

#include <limits.h>
#include <unistd.h>

#include "access/xact.h"
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
int			tdc_guc_memory_ceiling_mb = 0;
bool		tdc_guc_stats = false;
int			tdc_guc_max_result_bytes = (int) MaxAllocSize;

/*
 * Half the physical memory in MB, or 0 when the system does not say.  Read
 * once at load: sysconf(_SC_PHYS_PAGES) is a sysinfo() system call, far too
 * slow for the per-row checks.
 */
static uint64 default_ceiling = 0;

static uint64
half_physical_memory_mb(void)
{
	long		pages = sysconf(_SC_PHYS_PAGES);
	long		pagesize = sysconf(_SC_PAGESIZE);

	if (pages <= 0 || pagesize <= 0)
		return 0;
	return (uint64) pages / 2 * (uint64) pagesize / (1024 * 1024);
}

uint64
tdc_memory_limit_mb(const char **setting)
{
	uint64		ceiling;

	if (tdc_guc_memory_ceiling_mb > 0)
		ceiling = (uint64) tdc_guc_memory_ceiling_mb;
	else if (tdc_guc_memory_ceiling_mb == 0)
		ceiling = default_ceiling;
	else
		ceiling = 0;

	if (tdc_guc_max_memory_mb > 0 &&
		(ceiling == 0 || (uint64) tdc_guc_max_memory_mb <= ceiling))
	{
		*setting = "tdc_delaunay.max_memory";
		return (uint64) tdc_guc_max_memory_mb;
	}
	*setting = "tdc_delaunay.memory_ceiling";
	return ceiling;
}

uint64
tdc_max_memory_bytes(void)
{
	const char *setting;

	return tdc_memory_limit_mb(&setting) * 1024 * 1024;
}

const char *
tdc_memory_limit_hint(void)
{
	const char *setting;

	(void) tdc_memory_limit_mb(&setting);
	if (strcmp(setting, "tdc_delaunay.memory_ceiling") == 0)
		return "tdc_delaunay.memory_ceiling caps tdc_delaunay.max_memory and only a superuser can raise it; or triangulate fewer points.";
	return "Raise tdc_delaunay.max_memory or triangulate fewer points.";
}

/* Bytes in MB, rounded up: an estimate over the limit never reads as under. */
static unsigned long long
mb_up(uint64 bytes)
{
	return (unsigned long long) ((bytes + (1 << 20) - 1) >> 20);
}

void
tdc_report_memory_limit(const char *fname, const char *what, uint64 need,
						uint64 result)
{
	const char *setting;
	uint64		limit = tdc_memory_limit_mb(&setting);

	if (result == 0)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: %s needs about %llu MB, more than %s (%llu MB)",
						fname, what, mb_up(need),
						setting, (unsigned long long) limit),
				 errhint("%s", tdc_memory_limit_hint())));
	ereport(ERROR,
			(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
			 errmsg("%s: %s needs about %llu MB and its result value %llu MB more, together more than %s (%llu MB)",
					fname, what, mb_up(need), mb_up(result),
					setting, (unsigned long long) limit),
			 errhint("%s", tdc_memory_limit_hint())));
	pg_unreachable();
}

void		_PG_init(void);

void
_PG_init(void)
{
	default_ceiling = half_physical_memory_mb();

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
							0, -1, TDC_MAX_LEVELS,
							PGC_USERSET, 0,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.max_memory",
							"Memory one triangulation may use (0 = up to tdc_delaunay.memory_ceiling).",
							"Counts the collected vertices, the engine's estimate and the result.",
							&tdc_guc_max_memory_mb,
							0, 0, INT_MAX,
							PGC_USERSET, GUC_UNIT_MB,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.keep_memory",
							"Memory of freed engine arrays a session keeps for its next triangulation (0 = none).",
							"Released tdc_delaunay.keep_memory_time after the last triangulation, and on any error.",
							&tdc_guc_keep_memory_mb,
							256, 0, INT_MAX,
							PGC_USERSET, GUC_UNIT_MB,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.keep_memory_time",
							"How long a session keeps freed engine arrays after its last triangulation (0 = not at all).",
							NULL,
							&tdc_guc_keep_memory_time_ms,
							10000, 0, INT_MAX,
							PGC_USERSET, GUC_UNIT_MS,
							NULL, NULL, NULL);

	DefineCustomIntVariable("tdc_delaunay.memory_ceiling",
							"Ceiling on tdc_delaunay.max_memory (0 = half the physical memory, -1 = none).",
							NULL,
							&tdc_guc_memory_ceiling_mb,
							0, -1, INT_MAX,
							PGC_SUSET, GUC_UNIT_MB,
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

	MarkGUCPrefixReserved("tdc_delaunay");

	/* PostGIS's cancel handler must never allocate: see signals.c */
	if (IsTransactionState())
		tdc_signal_settle();
}
