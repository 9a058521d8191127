/*
 * bounded_mem.c -- the memory of a run in tiles (./tdc --max-memory)
 *
 * --max-memory is a limit on the process's peak resident size, which the
 * tiles' model (tdc_tp_tile_bytes) does not see whole.  Three things stand
 * between the model and the peak, and each is dealt with here:
 *
 * - What the process holds beside a tile's arrays: its own pages and
 *   libraries, and the plan's prefix sums, kept for the first regions.  It
 *   is taken off the limit before the plan (heap_start), so tiles are cut
 *   for what is left.  Left out, 9 tight clusters under 18 MB peaked at
 *   16.1 MB where the model said 12.4.
 * - What the heap keeps.  Every tile allocates and frees the same large
 *   arrays, so the heap is kept rather than handed back at each free
 *   (served by mmap, 10M uniform points under 400 MB took 11.1 s against
 *   5.4 s, the pages faulted in and zeroed on every run).  But a kept heap
 *   also keeps what the scan and the bins freed, and the holes between
 *   arrays that grow by a few cells on each rerun: the same clusters crept
 *   from 16.1 to 18.0 MB over 87 runs, more under load, where the threads'
 *   allocations interleave differently.  heap_settle hands the free heap
 *   back after the bins, and after any run that leaves the process above
 *   3/4 of the limit; the next run starts from what is live.
 * - What the run needs before its first tile: read buffers, two counting
 *   grids, the sample and the halo index, some 10 MB whatever the limit.
 *   A limit below what was held by then is an error (before_tiles), not a
 *   silent overrun.
 */
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "bounded.h"

/* The process's resident bytes (/proc/self/statm), 0 where unknown. */
static size_t
resident_bytes(void)
{
	FILE	   *f = fopen("/proc/self/statm", "r");
	unsigned long size,
				resident = 0;

	if (f == NULL)
		return 0;
	if (fscanf(f, "%lu %lu", &size, &resident) != 2)
		resident = 0;
	fclose(f);
	return (size_t) resident * (size_t) sysconf(_SC_PAGESIZE);
}

/*
 * r->outside and r->budget from r->limit, at the start of the run; the
 * heap kept from here on.  Where the resident size is unknown, the
 * process's own pages are taken as 2 MB (1.8 MB for ./tdc on three points).
 */
void
heap_start(bounded_run *r)
{
	size_t		base = resident_bytes();

	r->outside = (base != 0 ? base : (size_t) 2 << 20) +
		sizeof(size_t) * (TDC_TP_GRID + 1) * (TDC_TP_GRID + 1);
	r->budget = r->limit > r->outside ? r->limit - r->outside : 0;
#ifdef __GLIBC__
	mallopt(M_MMAP_MAX, 0);
	mallopt(M_TRIM_THRESHOLD, INT32_MAX);
#endif
}

/*
 * The free heap handed back: always, or when the process holds more than
 * 3/4 of the limit.  Where the resident size is unknown, always.
 */
void
heap_settle(const bounded_run *r, bool always)
{
#ifdef __GLIBC__
	size_t		now;

	if (!always && (now = resident_bytes()) != 0 && now <= r->limit / 4 * 3)
		return;
	(void) malloc_trim(0);
#else
	(void) r;
	(void) always;
#endif
}

/* The peak so far against the limit, before any tile; dies when above it. */
void
before_tiles(const bounded_run *r)
{
	struct rusage ru;
	size_t		peak;
	char		msg[200];

	if (getrusage(RUSAGE_SELF, &ru) != 0)
		return;
	peak = (size_t) ru.ru_maxrss << 10;
	if (peak <= r->limit)
		return;
	snprintf(msg, sizeof(msg), "--max-memory %zu is below the %zu MB this run held before its first tile",
			 r->limit >> 20, (peak >> 20) + 1);
	die(1, "%s (read buffers, the counting grid and the halo index); raise it", msg);
}
