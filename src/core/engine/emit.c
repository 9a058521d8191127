/*
 * emit.c
 *		Handing a finished triangulation's triangles to the host in
 *		parallel (tdc_job_emit_start).
 *
 * A host that turns two million triangles into one output value spends as
 * long walking the mesh and writing bytes as the engine spent building it,
 * and on one thread.  The walk is the same as tdc_next_triangle's: a
 * triangle is reported at its smallest half-edge (tdc_tri_at), so the
 * half-edge array can be cut into ranges that are walked independently.
 *
 * The host writes triangle k at a position computed from k, so every range
 * must know its first triangle number before it hands anything over.  The
 * walk is what costs: each half-edge leads to two random loads in a mesh far
 * bigger than the caches.  So the mesh is walked once.  The first pass
 * collects each range's triangles, three site numbers each, into chunks of
 * a list shared by all ranges (a chunk is claimed with one atomic add, so
 * ranges never wait for each other); a prefix sum of the per-range counts
 * gives each range its first number; the second pass hands each range's
 * chunks over in order, reading the list sequentially.  Walking twice, once
 * to count and once to write, would pay the random loads twice.
 * The list costs 12 bytes per triangle while it lives, plus at most one
 * partly filled chunk per range.
 *
 * The order is exactly tdc_next_triangle's, so the host's bytes are the same
 * as a serial writer's, whatever the thread count.  Both passes poll the
 * cancel flag at least once per chunk, so a cancel is answered as fast as
 * during the triangulation.
 *
 * A small job (TDC_INLINE_MAX) has no pool: tdc_emit_inline hands its
 * triangles over on the caller's thread, in the same order.
 */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "job_int.h"

#define CHUNK			1024	/* triangles per chunk, and per callback */
#define PREFETCH		16		/* half-edges ahead: see collect_task */
#define RANGE_MIN		65536	/* half-edges per range, at least */
#define RANGES_PER_THREAD 16	/* for balance: faces are not spread evenly */
#define EMIT_INLINE_BATCH	256	/* triangles per callback of a small job */

typedef struct emit_plan
{
	tdc_job    *job;
	size_t		nhe;
	size_t		nranges;
	size_t	   *first;			/* nranges + 1: first triangle of each range */
	uint32_t   *head;			/* nranges: a range's first chunk, or NIL */
	uint32_t   *link;			/* nchunks: the next chunk of the same range */
	uint32_t   *tri;			/* nchunks * CHUNK triangles, 3 sites each */
	size_t		nchunks;
	atomic_size_t claimed;		/* chunks handed out so far */
} emit_plan;

static size_t
range_start(const emit_plan *p, size_t r)
{
	return p->nhe / p->nranges * r + (r < p->nhe % p->nranges ? r : p->nhe % p->nranges);
}

static bool
emit_cancelled(const tdc_job *job)
{
	return atomic_load_explicit(&job->cancel, memory_order_relaxed) != 0;
}

/*
 * Pass 1: the triangles of range r into the range's chain of chunks.  Every
 * chunk but the last of a range is full, which is all pass 2 needs to know
 * besides the count.  A range claims a chunk only for a triangle it found,
 * so the ranges together never need more than ntri / CHUNK + nranges chunks;
 * running out means the mesh holds more triangles than count_result() found.
 */
static void
collect_task(void *arg, size_t r, int worker)
{
	emit_plan  *p = arg;
	tdc_job    *job = p->job;
	size_t		lo = range_start(p, r),
				hi = range_start(p, r + 1),
				n = 0;
	uint32_t   *link = &p->head[r];
	uint32_t   *out = NULL;
	size_t		used = CHUNK;
	uint32_t	v[3];
	const tdc_he *he = job->he;

	*link = TDC_NIL;
	for (size_t h = lo; h < hi; h++)
	{
		/*
		 * The load that misses is the twin of the next half-edge around the
		 * face; ask for it a few half-edges early (a tenth less time here).
		 * A free slot's link may be anything: only prefetch inside the mesh.
		 */
		if (h + PREFETCH < hi)
		{
			uint32_t	ahead = he[SYM(h + PREFETCH)].prev;

			if (ahead < p->nhe)
				__builtin_prefetch(&he[SYM(ahead)]);
		}
		if (!tdc_tri_at(job, h, v))
			continue;
		if (used == CHUNK)
		{
			size_t		c = atomic_fetch_add_explicit(&p->claimed, 1,
													  memory_order_relaxed);

			if (c >= p->nchunks)
			{
				tdc_job_fail(job, TDC_EINVAL, "the mesh holds more than the %zu triangles counted",
							 job->ntri);
				return;
			}
			if (emit_cancelled(job))
				return;
			*link = (uint32_t) c;
			link = &p->link[c];
			*link = TDC_NIL;
			out = p->tri + c * (3 * CHUNK);
			used = 0;
		}
		out[3 * used] = v[0];
		out[3 * used + 1] = v[1];
		out[3 * used + 2] = v[2];
		used++;
		n++;
	}
	p->first[r + 1] = n;
}

/* Pass 2: range r's chunks to the host, one callback per chunk. */
static void
write_task(void *arg, size_t r, int worker)
{
	emit_plan  *p = arg;
	tdc_job    *job = p->job;
	size_t		next = p->first[r],
				left = p->first[r + 1] - next;

	for (uint32_t c = p->head[r]; left > 0; c = p->link[c])
	{
		size_t		k = left < CHUNK ? left : CHUNK;

		if (emit_cancelled(job))
			return;
		job->emit(job->emit_arg, next, k, p->tri + (size_t) c * (3 * CHUNK));
		next += k;
		left -= k;
	}
}

static void
plan_free(emit_plan *p)
{
	free(p->first);
	free(p->head);
	free(p->link);
	tdc_big_free(p->job->opt.cache, p->tri);
}

/* Ranges of half-edges to collect from: several per thread, none tiny. */
static size_t
plan_ranges(size_t nhe, int threads)
{
	size_t		nranges = (size_t) threads * RANGES_PER_THREAD;

	if (nranges > nhe / RANGE_MIN)
		nranges = nhe / RANGE_MIN;
	return nranges < 1 ? 1 : nranges;
}

size_t
tdc_emit_memory(size_t n, int threads)
{
	size_t		nranges = plan_ranges(n * 6, threads),
				nchunks = 2 * n / CHUNK + nranges;

	return nchunks * (3 * CHUNK * sizeof(uint32_t) + sizeof(uint32_t)) +
		nranges * (sizeof(size_t) + sizeof(uint32_t)) + 2 * sizeof(size_t);
}

/*
 * Runs on the driver thread.  The triangle count must come out as the one
 * count_result() found; anything else means the mesh is not what the
 * caller's buffer was sized for, and nothing more is emitted.
 */
int
tdc_emit_phase(tdc_job *job)
{
	emit_plan	p;
	int			rc;

	if (job->ntri == 0)
		return TDC_OK;
	rc = tdc_pool_create(&job->pool, job->threads);
	if (rc != 0)
	{
		/* on TDC_ETHREAD the pool left pthread_create's error in errno */
		tdc_job_fail(job, rc, rc == TDC_ETHREAD ? "could not create worker threads: %s" : "out of memory%s",
					 rc == TDC_ETHREAD ? strerror(errno) : "");
		return rc;
	}
	memset(&p, 0, sizeof(p));
	p.job = job;
	p.nhe = job->nin * 6;
	p.nranges = plan_ranges(p.nhe, job->threads);
	p.nchunks = job->ntri / CHUNK + p.nranges;
	atomic_init(&p.claimed, 0);
	p.first = calloc(p.nranges + 1, sizeof(size_t));
	p.head = malloc(p.nranges * sizeof(uint32_t));
	p.link = malloc(p.nchunks * sizeof(uint32_t));
	/* read only where collect_task wrote */
	p.tri = tdc_big_alloc_uninit(job->opt.cache, p.nchunks * (3 * CHUNK) * sizeof(uint32_t));
	if (p.first == NULL || p.head == NULL || p.link == NULL || p.tri == NULL)
	{
		plan_free(&p);
		tdc_job_fail(job, TDC_ENOMEM, "out of memory listing the triangles");
		return TDC_ENOMEM;
	}

	tdc_pool_for(job->pool, p.nranges, collect_task, &p);
	if (emit_cancelled(job) || atomic_load(&job->failed))
	{
		plan_free(&p);
		return emit_cancelled(job) ? TDC_ECANCELED : atomic_load(&job->failed);
	}
	for (size_t r = 0; r < p.nranges; r++)
		p.first[r + 1] += p.first[r];
	if (p.first[p.nranges] != job->ntri)
	{
		tdc_job_fail(job, TDC_EINVAL, "the mesh holds %zu triangles, %zu were counted",
					 p.first[p.nranges], job->ntri);
		plan_free(&p);
		return TDC_EINVAL;
	}
	tdc_pool_for(job->pool, p.nranges, write_task, &p);
	plan_free(&p);
	return emit_cancelled(job) ? TDC_ECANCELED : TDC_OK;
}

/*
 * A small job's triangles, handed over on the caller's thread in batches in
 * the order of tdc_next_triangle, with none of emit.c's planning.
 */
int
tdc_emit_inline(tdc_job *job)
{
	uint32_t	v[3 * EMIT_INLINE_BATCH];
	tdc_iter	it = {0};
	size_t		first = 0,
				k = 0;

	while (tdc_next_triangle(job, &it, v + 3 * k))
	{
		if (++k == EMIT_INLINE_BATCH)
		{
			job->emit(job->emit_arg, first, k, v);
			first += k;
			k = 0;
		}
	}
	if (k > 0)
		job->emit(job->emit_arg, first, k, v);
	return first + k == job->ntri ? TDC_OK : TDC_EINVAL;
}
