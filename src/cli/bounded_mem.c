/*
 * bounded_mem.c -- the process's memory around a run in tiles (./tdc --max-memory)
 *
 * --max-memory is a limit on the process's peak resident size, which the
 * tiles' model (tdc_tp_tile_bytes) does not see whole.  Three things stand
 * between the model and the peak; the core's bounded run (tdc_bounded_run)
 * knows the process only through what this file hands it:
 *
 * - What the process holds beside a tile's arrays: its own pages and
 *   libraries.  It is measured before the run and passed as `outside`,
 *   which the run takes off the limit (with the plan's prefix sums, kept
 *   for the first regions) before the plan, so tiles are cut for what is
 *   left.  Left out, 9 tight clusters under 18 MB peaked at 16.1 MB where
 *   the model said 12.4.
 * - What the heap keeps.  Every tile allocates and frees the same large
 *   arrays, so the heap is kept rather than handed back at each free
 *   (served by mmap, 10M uniform points under 400 MB took 11.1 s against
 *   5.4 s, the pages faulted in and zeroed on every run).  But a kept heap
 *   also keeps what the scan and the bins freed, and the holes between
 *   arrays that grow by a few cells on each rerun: the same clusters crept
 *   from 16.1 to 18.0 MB over 87 runs, more under load, where the threads'
 *   allocations interleave differently.  The settle callback hands the
 *   free heap back after the bins, and after any run that leaves the
 *   process above 3/4 of the limit; the next run starts from what is live.
 * - What the run needs before its first tile: read buffers, two counting
 *   grids, the sample and the halo index, some 10 MB whatever the limit.
 *   The peak callback gives the run the process's peak so far, and a limit
 *   below it is an error, not a silent overrun.
 */
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "cli.h"

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

/* the limit of the process's one run in tiles, for heap_settle */
static size_t heap_limit;

size_t
heap_resident(void)
{
	return resident_bytes();
}

/*
 * At the start of the run: what the process holds (its resident size,
 * rounded up to a whole MB; where unknown, 2 MB, what ./tdc holds on three
 * points: 1.8 MB); the heap kept from here on, and settled against limit.
 * The rounding keeps the plan from the pages the address layout happens to
 * touch: the same run measured 2.26 to 2.38 MB, and a budget that much
 * larger cut the Stockholm coastline into 16 tiles instead of 18, one of
 * which natural neighbour then refused under 20 MB.
 */
size_t
heap_start(size_t limit)
{
	size_t		base = resident_bytes(),
				mb = (size_t) 1 << 20;

	heap_limit = limit;
#ifdef __GLIBC__
	mallopt(M_MMAP_MAX, 0);
	mallopt(M_TRIM_THRESHOLD, INT32_MAX);
#endif
	return base != 0 ? (base + mb - 1) / mb * mb : (size_t) 2 << 20;
}

/*
 * The run's settle callback (arg unused): the free heap handed back
 * always, or when the process holds more than 3/4 of heap_start's limit.
 * Where the resident size is unknown, always.
 */
void
heap_settle(void *arg, bool always)
{
	(void) arg;
#ifdef __GLIBC__
	size_t		now;

	if (!always && (now = resident_bytes()) != 0 && now <= heap_limit / 4 * 3)
		return;
	(void) malloc_trim(0);
#else
	(void) always;
#endif
}

/* The run's peak callback (arg unused): the process's peak resident bytes so far, 0 where unknown. */
size_t
heap_peak(void *arg)
{
	struct rusage ru;

	if (getrusage(RUSAGE_SELF, &ru) != 0)
		return 0;
	return (size_t) ru.ru_maxrss << 10;
}
