/*
 * pool.c
 *		A pthread pool that runs one parallel-for at a time.
 *
 * Every phase of the twofold divide and conquer is a loop over independent
 * tasks (grid subdivision of the nodes of one tree level, the subsets, the
 * merges of one tree level), separated by barriers.  So the pool offers just
 * tdc_pool_for(): the calling thread publishes the loop, takes part in it,
 * and returns when every task has finished.  Tasks are claimed one at a time
 * from an atomic counter, which balances subsets of uneven cost.
 *
 * The pool has no global state: each job owns one.  Its threads are created
 * by the job's driver thread, which the job started with every signal
 * blocked, so they inherit a full signal mask and never take a signal meant
 * for the host process (a PostgreSQL backend).
 */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "engine_int.h"

struct tdc_pool
{
	pthread_mutex_t lock;
	pthread_cond_t wake;			/* a new loop or shutdown */
	pthread_cond_t idle;			/* a worker finished its part of a loop */
	pthread_t  *threads;
	int			nthreads;			/* helper threads, besides the caller */
	int			started;

	/* The current loop. */
	unsigned long generation;
	tdc_task_fn fn;
	void	   *arg;
	size_t		ntasks;
	atomic_size_t next;
	int			busy;				/* helpers still inside the current loop */
	bool		shutdown;
};

typedef struct worker_arg
{
	tdc_pool   *pool;
	int			id;
} worker_arg;

static void
run_tasks(tdc_pool *pool, tdc_task_fn fn, void *arg, size_t ntasks, int worker)
{
	for (;;)
	{
		size_t		i = atomic_fetch_add(&pool->next, 1);

		if (i >= ntasks)
			break;
		fn(arg, i, worker);
	}
}

static void *
worker_main(void *p)
{
	worker_arg *wa = p;
	tdc_pool   *pool = wa->pool;
	int			id = wa->id;
	unsigned long seen = 0;

	free(wa);
	pthread_mutex_lock(&pool->lock);
	for (;;)
	{
		tdc_task_fn fn;
		void	   *arg;
		size_t		ntasks;

		while (!pool->shutdown && pool->generation == seen)
			pthread_cond_wait(&pool->wake, &pool->lock);
		if (pool->shutdown)
			break;
		seen = pool->generation;
		fn = pool->fn;
		arg = pool->arg;
		ntasks = pool->ntasks;
		pthread_mutex_unlock(&pool->lock);

		run_tasks(pool, fn, arg, ntasks, id);

		pthread_mutex_lock(&pool->lock);
		if (--pool->busy == 0)
			pthread_cond_signal(&pool->idle);
	}
	pthread_mutex_unlock(&pool->lock);
	return NULL;
}

/*
 * Create a pool of nthreads threads in all, the caller included (none, a
 * NULL pool, for one thread: the caller runs every loop).  Returns 0
 * or TDC_ENOMEM / TDC_ETHREAD with nothing left behind; after TDC_ETHREAD,
 * errno holds pthread_create's error, which pthread_create returns instead
 * of setting errno (errno then holds whatever its internals left, such as
 * ENOMEM from the stack's mmap).
 */
int
tdc_pool_create(tdc_pool **out, int nthreads)
{
	tdc_pool   *pool;

	/* one thread: no pool at all, tdc_pool_for runs the loop itself */
	*out = NULL;
	if (nthreads <= 1)
		return 0;
	pool = calloc(1, sizeof(tdc_pool));
	if (pool == NULL)
		return TDC_ENOMEM;
	pool->nthreads = nthreads > 1 ? nthreads - 1 : 0;
	pool->threads = calloc(pool->nthreads + 1, sizeof(pthread_t));
	if (pool->threads == NULL)
	{
		free(pool);
		return TDC_ENOMEM;
	}
	pthread_mutex_init(&pool->lock, NULL);
	pthread_cond_init(&pool->wake, NULL);
	pthread_cond_init(&pool->idle, NULL);
	atomic_init(&pool->next, 0);
	for (int i = 0; i < pool->nthreads; i++)
	{
		worker_arg *wa = malloc(sizeof(worker_arg));
		int			err = 0;

		if (wa == NULL || (wa->pool = pool, wa->id = i + 1,
						   (err = pthread_create(&pool->threads[i], NULL, worker_main, wa)) != 0))
		{
			int			rc = wa == NULL ? TDC_ENOMEM : TDC_ETHREAD;

			free(wa);
			tdc_pool_destroy(pool);
			if (rc == TDC_ETHREAD)
				errno = err;	/* last: the clean-up may change errno */
			return rc;
		}
		pool->started++;
	}
	*out = pool;
	return 0;
}

/* Run fn(arg, i, worker) for i in [0, ntasks) on all threads; worker 0 is the caller. */
void
tdc_pool_for(tdc_pool *pool, size_t ntasks, tdc_task_fn fn, void *arg)
{
	if (ntasks == 0)
		return;
	if (pool == NULL || pool->started == 0 || ntasks == 1)
	{
		for (size_t i = 0; i < ntasks; i++)
			fn(arg, i, 0);
		return;
	}
	pthread_mutex_lock(&pool->lock);
	pool->fn = fn;
	pool->arg = arg;
	pool->ntasks = ntasks;
	atomic_store(&pool->next, 0);
	pool->busy = pool->started;
	pool->generation++;
	pthread_cond_broadcast(&pool->wake);
	pthread_mutex_unlock(&pool->lock);

	run_tasks(pool, fn, arg, ntasks, 0);

	pthread_mutex_lock(&pool->lock);
	while (pool->busy > 0)
		pthread_cond_wait(&pool->idle, &pool->lock);
	pthread_mutex_unlock(&pool->lock);
}

void
tdc_pool_destroy(tdc_pool *pool)
{
	if (pool == NULL)
		return;
	pthread_mutex_lock(&pool->lock);
	pool->shutdown = true;
	pthread_cond_broadcast(&pool->wake);
	pthread_mutex_unlock(&pool->lock);
	for (int i = 0; i < pool->started; i++)
		pthread_join(pool->threads[i], NULL);
	pthread_mutex_destroy(&pool->lock);
	pthread_cond_destroy(&pool->wake);
	pthread_cond_destroy(&pool->idle);
	free(pool->threads);
	free(pool);
}
