/*
 * mem.c
 *		The big arrays of a run, and the cache a host may keep them in
 *		between runs.
 *
 * A job's arrays grow with its input: a million points map some 120 MB of
 * mesh, coordinates, orders and triangle lists.  Big arrays are mapped and
 * unmapped directly, so that their memory goes back to the system when the
 * job is freed, whatever malloc's thresholds have drifted to in a long-lived
 * host process (a PostgreSQL backend raises them after every big free).
 * Small ones come from malloc: a small job's arrays are cheaper to take from
 * the heap than to map, fault in and unmap.  Either way the memory comes
 * zeroed and 64-aligned, with its size and origin in a header in front.
 *
 * Page faults.  Every 4 kB page of a fresh mapping is a fault, a page the
 * kernel zeroes and, at unmap, a TLB shootdown on every CPU the threads ran
 * on: 29% of the CPU time of a million-point aggregate in a backend went
 * to the kernel for its arrays and its result.  Two things help.
 * tdc_prefault maps a range in with one system call where a writer is about
 * to fill it.  And a host that runs one big triangulation after another (a
 * GROUP BY of big groups, a session repeating a query) can give its jobs a
 * tdc_cache (options.cache): a freed mapping is then kept, up to the
 * cache's limit, and a later array of the same size or a little less takes
 * it back, cut to size and cleared with memset, with no fault at all.  The
 * cache is the host's object; the core keeps no memory of its own between
 * runs.  The host chooses the limit and when to give the memory back
 * (tdc_cache_trim), and a mapping the cache has no room for is unmapped as
 * before, so a run's memory is never more than without the cache plus the
 * limit.
 *
 * Transparent huge pages where they are cheap.  A 2 MB page is one fault
 * instead of 512, and one TLB entry: when memory was freed a moment before,
 * 160 MB are mapped in at some 20 GB/s, against 3-5 GB/s in 4 kB pages.  But
 * on a virtual machine whose host takes back the memory a guest leaves free
 * (free page reporting, which hands back whole 2 MB blocks), a huge page that
 * was not in use a moment before costs some 4 ms to fault in: 0.4-0.7 GB/s
 * (bench/first_touch.c prints both).  Which case holds depends on what ran
 * in the last seconds, so tdc_advise_huge asks: it maps in huge pages one by
 * one, timing each, and once one takes longer than the 512 small faults it
 * replaces would, the rest stays in 4 kB pages.  A result value goes through
 * it whole, in slices; an engine array only its first 32 MB (advise_array).
 * A kept mapping keeps the pages it was first given.
 */
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/mman.h>
#include <unistd.h>

#include "engine_int.h"

#define BIG_HEADER		64
#define HUGE_SIZE		((size_t) 2 << 20)
/* a huge page's fault, above which 4 kB pages are cheaper: 512 faults of ~1.3 us */
#define HUGE_PROBE_MAX_NS	700000
#define BIG_MAP_MIN		((size_t) 256 << 10)
#define PREFAULT_MIN	((size_t) 64 << 10)
#define CACHE_SLOTS		32
/* a kept mapping is cut to size when it is this much bigger than asked */
#define CACHE_CUT_MIN	((size_t) 64 << 10)

typedef struct big_header
{
	size_t		total;			/* bytes from the header on; mapped: page multiple */
	void	   *heap;			/* malloc'd block to free, or NULL: mapped */
} big_header;

/*
 * Kept mappings, each whole (header included), none in use, the longest
 * kept first.  Invariant: kept is the sum of slot[0..n).total, at most limit.
 */
struct tdc_cache
{
	pthread_mutex_t lock;
	size_t		limit;
	size_t		kept;
	int			n;
	struct
	{
		char	   *base;
		size_t		total;
	}			slot[CACHE_SLOTS];
};

static size_t
page_size(void)
{
	long		ps = sysconf(_SC_PAGESIZE);

	return ps > 0 ? (size_t) ps : 4096;
}

static size_t
page_round(size_t n)
{
	size_t		ps = page_size();

	return (n + ps - 1) & ~(ps - 1);
}

/* Remove slot i, keeping the others in the order they were kept. */
static void
cache_drop(tdc_cache *c, int i)
{
	c->kept -= c->slot[i].total;
	memmove(&c->slot[i], &c->slot[i + 1], (size_t) (c->n - i - 1) * sizeof(c->slot[0]));
	c->n--;
}

/*
 * The smallest kept mapping of total bytes up to half as much again, taken
 * out of the cache and cut down to total; NULL if there is none.  A bigger
 * one is left for the bigger array it probably came from.
 */
static char *
cache_take(tdc_cache *c, size_t total)
{
	int			best = -1;
	char	   *p;
	size_t		have;

	if (pthread_mutex_lock(&c->lock) != 0)
		return NULL;
	for (int i = 0; i < c->n; i++)
		if (c->slot[i].total >= total && c->slot[i].total - total <= total / 2 &&
			(best < 0 || c->slot[i].total < c->slot[best].total))
			best = i;
	if (best < 0)
	{
		pthread_mutex_unlock(&c->lock);
		return NULL;
	}
	p = c->slot[best].base;
	have = c->slot[best].total;
	cache_drop(c, best);
	pthread_mutex_unlock(&c->lock);

	/* the run's memory is what it asked for, as without the cache */
	if (have - total >= CACHE_CUT_MIN)
	{
		(void) munmap(p + total, have - total);
		have = total;
	}
	((big_header *) p)->total = have;
	return p;
}

/*
 * Keep a whole mapping, unmapping the longest-kept ones if that makes room
 * for it; false if it cannot be kept: the caller unmaps it.
 */
static bool
cache_put(tdc_cache *c, char *base, size_t total)
{
	bool		kept = false;

	if (pthread_mutex_lock(&c->lock) != 0)
		return false;
	if (total <= c->limit)
	{
		while (c->n > 0 && (c->n == CACHE_SLOTS || total > c->limit - c->kept))
		{
			(void) munmap(c->slot[0].base, c->slot[0].total);
			cache_drop(c, 0);
		}
		c->slot[c->n].base = base;
		c->slot[c->n].total = total;
		c->n++;
		c->kept += total;
		kept = true;
	}
	pthread_mutex_unlock(&c->lock);
	return kept;
}

static void advise_array(char *p, size_t total);

/*
 * Zeroed or not: an array whose every byte its user writes before reading
 * it needs no clearing, and a kept mapping of the mesh is some 70 MB of
 * memset a run would pay on one thread.  A fresh mapping is zero anyway.
 */
static void *
big_alloc(tdc_cache *cache, size_t size, bool zero)
{
	size_t		total = size + BIG_HEADER;
	char	   *p;
	big_header *h;

	if (total < size)
		return NULL;
	if (total < BIG_MAP_MIN)
	{
		char	   *raw = malloc(total + BIG_HEADER);

		if (raw == NULL)
			return NULL;
		p = (char *) (((uintptr_t) raw + BIG_HEADER - 1) & ~(uintptr_t) (BIG_HEADER - 1));
		if (zero)
			memset(p, 0, total);
		h = (big_header *) p;
		h->heap = raw;
		h->total = total;
		return p + BIG_HEADER;
	}
	total = page_round(total);
	if (total < size)
		return NULL;
	if (cache != NULL && (p = cache_take(cache, total)) != NULL)
	{
		if (zero)
			memset(p + BIG_HEADER, 0, size);
	}
	else
	{
		p = mmap(NULL, total, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
		if (p == MAP_FAILED)
			return NULL;
		((big_header *) p)->total = total;
		advise_array(p, total);
	}
	((big_header *) p)->heap = NULL;
	return p + BIG_HEADER;
}

void *
tdc_big_alloc(tdc_cache *cache, size_t size)
{
	return big_alloc(cache, size, true);
}

void *
tdc_big_alloc_uninit(tdc_cache *cache, size_t size)
{
	return big_alloc(cache, size, false);
}

void
tdc_big_free(tdc_cache *cache, void *ptr)
{
	big_header *h;

	if (ptr == NULL)
		return;
	h = (big_header *) ((char *) ptr - BIG_HEADER);
	if (h->heap)
		free(h->heap);
	else if (cache == NULL || !cache_put(cache, (char *) h, h->total))
		munmap(h, h->total);
}

static long long
elapsed_ns(const struct timespec *a, const struct timespec *b)
{
	return (long long) (b->tv_sec - a->tv_sec) * 1000000000LL + (b->tv_nsec - a->tv_nsec);
}

/*
 * Huge pages over the 2 MB-aligned interior of [p, p + len) of fresh
 * memory, mapped in one at a time for as long as each comes faster than 4
 * kB pages would (see above); from the first that does not, the rest of
 * the array stays in 4 kB pages, left to its writers.  One at a time,
 * because the kernel hands out the free blocks it has not yet reported to
 * the host first: a big array gets warm huge pages until they run out,
 * then cold ones, and a probe of its first page alone said nothing of its
 * last.  Only the interior: a huge page never reaches past the array, so
 * the resident size stays what the arrays use.  Arrays under 8 MB are left
 * alone: the probe would be a large part of them.  Mapping in warm huge
 * pages costs about 0.1 ms each, on the calling thread, with no cancel
 * check: a host maps a big value in slices (tdc_advise_result).  Returns
 * false if it met a slow page, and the next slices should not ask.
 */
bool
tdc_advise_huge(void *ptr, size_t len)
{
#if defined(MADV_HUGEPAGE) && defined(MADV_NOHUGEPAGE) && defined(MADV_POPULATE_WRITE)
	uintptr_t	a = ((uintptr_t) ptr + HUGE_SIZE - 1) & ~(uintptr_t) (HUGE_SIZE - 1),
				b = ((uintptr_t) ptr + len) & ~(uintptr_t) (HUGE_SIZE - 1);

	if (len < 4 * HUGE_SIZE || b <= a + HUGE_SIZE)
		return true;
	if (madvise((void *) a, b - a, MADV_HUGEPAGE) != 0)
		return false;
	for (uintptr_t p = a; p < b; p += HUGE_SIZE)
	{
		struct timespec t0,
					t1;

		clock_gettime(CLOCK_MONOTONIC, &t0);
		(void) madvise((void *) p, HUGE_SIZE, MADV_POPULATE_WRITE);
		clock_gettime(CLOCK_MONOTONIC, &t1);
		if (elapsed_ns(&t0, &t1) > HUGE_PROBE_MAX_NS)
		{
			if (p + HUGE_SIZE < b)
				(void) madvise((void *) (p + HUGE_SIZE), b - p - HUGE_SIZE, MADV_NOHUGEPAGE);
			return false;
		}
	}
	return true;
#else
	(void) ptr;
	(void) len;
	return false;
#endif
}

/*
 * The same for one of the engine's arrays, mapped by a thread that polls no
 * cancel flag meanwhile: only the first ARRAY_PROBE bytes are mapped in
 * page by page; if all of those came fast, the rest asks for huge pages
 * too and is faulted in by the array's writers, each in its own part.  A
 * kept array is not asked again.
 */
#define ARRAY_PROBE		((size_t) 32 << 20)

static void
advise_array(char *p, size_t total)
{
#if defined(MADV_HUGEPAGE)
	uintptr_t	cut = ((uintptr_t) p + ARRAY_PROBE) & ~(uintptr_t) (HUGE_SIZE - 1),
				b = ((uintptr_t) p + total) & ~(uintptr_t) (HUGE_SIZE - 1);

	if (total <= ARRAY_PROBE + HUGE_SIZE)
		(void) tdc_advise_huge(p, total);
	else if (tdc_advise_huge(p, cut - (uintptr_t) p) && b > cut)
		(void) madvise((void *) cut, b - cut, MADV_HUGEPAGE);
#else
	(void) p;
	(void) total;
#endif
}

void
tdc_prefault(void *ptr, size_t len)
{
#ifdef MADV_POPULATE_WRITE
	uintptr_t	page = page_size(),
				a,
				b;

	/* a system call costs more than faulting in a few pages */
	if (len < PREFAULT_MIN)
		return;
	a = (uintptr_t) ptr & ~(page - 1);
	b = ((uintptr_t) ptr + len + page - 1) & ~(page - 1);
	(void) madvise((void *) a, b - a, MADV_POPULATE_WRITE);
#else
	(void) ptr;
	(void) len;
#endif
}

tdc_cache *
tdc_cache_create(size_t limit)
{
	tdc_cache  *c = calloc(1, sizeof(tdc_cache));

	if (c == NULL)
		return NULL;
	if (pthread_mutex_init(&c->lock, NULL) != 0)
	{
		free(c);
		return NULL;
	}
	c->limit = limit;
	return c;
}

/*
 * Unmap kept mappings, the longest-kept first, until at most keep bytes are
 * kept.  Only takes the lock if it is free, so that a host may call it from a signal handler that
 * interrupted nothing of ours; returns false, doing nothing, if the lock was
 * held.
 */
bool
tdc_cache_trim(tdc_cache *c, size_t keep)
{
	if (c == NULL)
		return true;
	if (pthread_mutex_trylock(&c->lock) != 0)
		return false;
	while (c->kept > keep && c->n > 0)
	{
		(void) munmap(c->slot[0].base, c->slot[0].total);
		cache_drop(c, 0);
	}
	pthread_mutex_unlock(&c->lock);
	return true;
}

void
tdc_cache_set_limit(tdc_cache *c, size_t limit)
{
	if (c == NULL)
		return;
	(void) tdc_cache_trim(c, limit);
	pthread_mutex_lock(&c->lock);
	c->limit = limit;
	pthread_mutex_unlock(&c->lock);
}

size_t
tdc_cache_kept(tdc_cache *c)
{
	size_t		kept;

	if (c == NULL || pthread_mutex_lock(&c->lock) != 0)
		return 0;
	kept = c->kept;
	pthread_mutex_unlock(&c->lock);
	return kept;
}

void
tdc_cache_destroy(tdc_cache *c)
{
	if (c == NULL)
		return;
	(void) tdc_cache_trim(c, 0);
	pthread_mutex_destroy(&c->lock);
	free(c);
}
