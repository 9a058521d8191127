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
 * Two passes over the ranges on the pool: the first counts the triangles
 * of each range, a prefix sum turns the counts into each range's first
 * triangle number, and the second walks again and hands the triangles over
 * in batches with their numbers.  The order is exactly tdc_next_triangle's,
 * so a host that writes triangle k at a position computed from k produces
 * the same bytes as a serial writer, whatever the thread count.
 *
 * Both passes poll the cancel flag once per batch, so a cancel is answered
 * as fast as during the triangulation.
 */
#include <stdlib.h>

#include "job.h"

#define EMIT_BATCH		1024	/* triangles per callback */
#define RANGE_MIN		65536	/* half-edges per range, at least */
#define RANGES_PER_THREAD 16	/* for balance: faces are not spread evenly */

typedef struct emit_plan
{
	tdc_job    *job;
	size_t		nhe;
	size_t		nranges;
	size_t	   *first;			/* nranges + 1: first triangle of each range */
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

static void
count_task(void *arg, size_t r, int worker)
{
	emit_plan  *p = arg;
	size_t		lo = range_start(p, r),
				hi = range_start(p, r + 1),
				n = 0;
	uint32_t	v[3];

	for (size_t h = lo; h < hi; h++)
	{
		if ((h & 0xffff) == 0 && emit_cancelled(p->job))
			return;
		n += tdc_tri_at(p->job, h, v);
	}
	p->first[r + 1] = n;
}

static void
write_task(void *arg, size_t r, int worker)
{
	emit_plan  *p = arg;
	tdc_job    *job = p->job;
	size_t		lo = range_start(p, r),
				hi = range_start(p, r + 1),
				next = p->first[r],
				k = 0;
	uint32_t	v[3 * EMIT_BATCH];

	for (size_t h = lo; h < hi; h++)
	{
		if (!tdc_tri_at(job, h, v + 3 * k))
			continue;
		if (++k == EMIT_BATCH)
		{
			if (emit_cancelled(job))
				return;
			job->emit(job->emit_arg, next, k, v);
			next += k;
			k = 0;
		}
	}
	if (k > 0)
		job->emit(job->emit_arg, next, k, v);
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
		tdc_job_fail(job, rc, "could not create worker threads");
		return rc;
	}
	p.job = job;
	p.nhe = job->nin * 6;
	p.nranges = (size_t) job->threads * RANGES_PER_THREAD;
	if (p.nranges > p.nhe / RANGE_MIN)
		p.nranges = p.nhe / RANGE_MIN;
	if (p.nranges < 1)
		p.nranges = 1;
	p.first = calloc(p.nranges + 1, sizeof(size_t));
	if (p.first == NULL)
	{
		tdc_job_fail(job, TDC_ENOMEM, "out of memory");
		return TDC_ENOMEM;
	}

	tdc_pool_for(job->pool, p.nranges, count_task, &p);
	if (emit_cancelled(job))
	{
		free(p.first);
		return TDC_ECANCELED;
	}
	for (size_t r = 0; r < p.nranges; r++)
		p.first[r + 1] += p.first[r];
	if (p.first[p.nranges] != job->ntri)
	{
		tdc_job_fail(job, TDC_EINVAL, "the mesh holds %zu triangles, %zu were counted",
					 p.first[p.nranges], job->ntri);
		free(p.first);
		return TDC_EINVAL;
	}
	tdc_pool_for(job->pool, p.nranges, write_task, &p);
	free(p.first);
	return emit_cancelled(job) ? TDC_ECANCELED : TDC_OK;
}
