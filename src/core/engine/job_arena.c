/*
 * job_arena.c
 *		The services every phase of a job calls: its arrays (from the
 *		arena of a small job, or mapped) and its first error.
 *
 * This is the bottom layer of a job: the phases (triangulate.c,
 * subdivide.c, emit.c, the leaves) allocate and fail through it, and it
 * calls nothing above itself, so no phase calls back up into the code that
 * runs it (job.c).  Only the thread that runs the phases allocates here.
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "job_int.h"

/*
 * 16-aligned memory for one of the job's arrays, zeroed unless the caller
 * fills it before reading it; NULL if out of memory.
 */
static void *
job_alloc(tdc_job *job, size_t size, bool zero)
{
	size_t		rounded = (size + TDC_ARENA_ALIGN - 1) & ~(size_t) (TDC_ARENA_ALIGN - 1);

	if (job->arena != NULL && rounded >= size &&
		rounded <= job->arena_size - job->arena_used)
	{
		void	   *p = job->arena + job->arena_used;

		job->arena_used += rounded;
		return zero ? memset(p, 0, size) : p;
	}
	job->off_arena = true;
	return zero ? tdc_big_alloc(job->opt.cache, size) :
		tdc_big_alloc_uninit(job->opt.cache, size);
}

void *
tdc_job_alloc(tdc_job *job, size_t size)
{
	return job_alloc(job, size, true);
}

void *
tdc_job_alloc_uninit(tdc_job *job, size_t size)
{
	return job_alloc(job, size, false);
}

void
tdc_job_release(tdc_job *job, void *ptr)
{
	char	   *p = ptr;

	if (p != NULL && job->arena != NULL && p >= job->arena && p < job->arena + job->arena_size)
		return;
	tdc_big_free(job->opt.cache, ptr);
}

void
tdc_job_free_arrays(tdc_job *job)
{
	/* the input map never comes from the arena (see above) */
	if (job->arena != NULL && !job->off_arena)
	{
		tdc_big_free(job->opt.cache, job->map);
		return;
	}
	tdc_job_release(job, job->xy);
	tdc_job_release(job, job->idx);
	tdc_job_release(job, job->site_of);
	tdc_job_release(job, job->map);
	tdc_job_release(job, job->outer);
	tdc_job_release(job, job->tol_to);
	tdc_job_release(job, job->he);
	tdc_job_release(job, job->prefix);
	tdc_job_release(job, job->node_rect);
	tdc_job_release(job, job->node_axis);
	tdc_job_release(job, job->node_lo);
	tdc_job_release(job, job->node_hi);
	tdc_job_release(job, job->subs);
}

void
tdc_job_fail(tdc_job *job, int code, const char *fmt,...)
{
	int			expected = 0;

	if (atomic_compare_exchange_strong(&job->failed, &expected, code))
	{
		va_list		ap;

		va_start(ap, fmt);
		vsnprintf(job->task_err, sizeof(job->task_err), fmt, ap);
		va_end(ap);
	}
	atomic_store(&job->cancel, 1);
}

