/*
 * mem_cache.c
 *		The backend's cache of the engine's big arrays between
 *		triangulations.
 *
 * A triangulation of a million points maps some 120 MB of arrays, and
 * faulting them in and unmapping them were part of the 29% of a million-point
 * aggregate's CPU time (the kernel zeroes every 4 kB page).  A backend that
 * triangulates again soon after (the next group of a GROUP BY, the same
 * report run again, a benchmark) can reuse the pages instead: the core's
 * tdc_cache keeps the arrays a job frees and gives them to the next job's
 * arrays of the same size, cleared with memset (mem.c).
 *
 * What a DBA must be able to count on:
 *	- the cache holds at most tdc_delaunay.keep_memory (0: nothing is kept,
 *	  every array is unmapped as it is freed);
 *	- it is emptied tdc_delaunay.keep_memory_time after the last
 *	  triangulation (a timeout, so an idle session gives its memory back),
 *	  when a transaction aborts, and when a triangulation ends in an error;
 *	- a triangulation under tdc_delaunay.max_memory first empties the cache
 *	  down to what its limit leaves over, so that kept arrays and the run's
 *	  own never add up past the limit.
 *
 * The timeout handler runs in a signal handler.  It only unmaps, and only
 * when the cache is not in use: every run switches the timeout off before
 * it touches the cache and on again once its arrays are freed, and the
 * core's trim only takes the cache's lock if it is free.  Error recovery
 * switches every timeout off; the abort callback empties the cache then,
 * and the reset callback of a failed run (run.c) empties it again
 * once the job's arrays are freed, the failed job's own going straight back
 * to the system (tdc_job_free_background), so nothing stays kept without a
 * timeout to release it.
 */
#include "postgres.h"

#include "access/xact.h"
#include "utils/timeout.h"

#include "tdc_pg.h"

int			tdc_guc_keep_memory_mb = 256;
int			tdc_guc_keep_memory_time_ms = 10000;

static tdc_cache *backend_cache = NULL;
static uint64 backend_limit = 0;	/* the limit last set on it */
static TimeoutId release_timeout;
static bool release_registered = false;

static void
release_on_abort(XactEvent event, void *arg)
{
	if (event == XACT_EVENT_ABORT || event == XACT_EVENT_PARALLEL_ABORT)
		tdc_backend_cache_release();
}

void
tdc_backend_cache_release(void)
{
	if (backend_cache != NULL)
		(void) tdc_cache_trim(backend_cache, 0);
}

/*
 * The cache for a run that leaves room bytes of tdc_delaunay.max_memory
 * unused: first trimmed to that room and to tdc_delaunay.keep_memory, then,
 * if use, returned with the release timeout switched off until
 * tdc_backend_cache_idle.  NULL when not to be used, when keep_memory is 0,
 * or when no cache could be made (the run then maps and unmaps as usual).
 * A run that does not use it costs no system call here, and nothing at all
 * unless its limit leaves less room than the cache may keep.
 */
tdc_cache *
tdc_backend_cache(uint64 room, bool use)
{
	uint64		limit = (uint64) tdc_guc_keep_memory_mb << 20;

	if (backend_cache == NULL)
	{
		if (!use || limit == 0)
			return NULL;
		backend_cache = tdc_cache_create((size_t) limit);
		if (backend_cache == NULL)
			return NULL;
		RegisterXactCallback(release_on_abort, NULL);
	}
	if (use && release_registered)
		disable_timeout(release_timeout, false);
	if (use || limit != backend_limit || room < limit)
	{
		/* kept under a higher setting, or more than this run leaves room for */
		tdc_cache_set_limit(backend_cache, (size_t) limit);
		(void) tdc_cache_trim(backend_cache, (size_t) Min(room, limit));
		backend_limit = limit;
	}
	if (!use || limit == 0)
		return NULL;
	if (!release_registered)
	{
		release_timeout = RegisterTimeout(USER_TIMEOUT, tdc_backend_cache_release);
		release_registered = true;
	}
	return backend_cache;
}

/* The run's arrays are freed: release what is kept if no run follows soon. */
void
tdc_backend_cache_idle(void)
{
	if (backend_cache == NULL || !release_registered)
		return;
	if (tdc_guc_keep_memory_time_ms <= 0)
		tdc_backend_cache_release();
	else
		enable_timeout_after(release_timeout, tdc_guc_keep_memory_time_ms);
}

/* For the stats DETAIL: what is kept now, in kB. */
unsigned long long
tdc_backend_cache_kept_kb(void)
{
	return (unsigned long long) (tdc_cache_kept(backend_cache) >> 10);
}
