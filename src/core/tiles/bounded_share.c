/*
 * bounded_share.c
 *		What the tile workers of a bounded run share: the memory budget,
 *		the tile files, the output, the tiles still to run and the first
 *		error.
 *
 * After binning, a tile's run reads only files (its own, its halo file,
 * its neighbours' cells) and decides its final triangles from the points
 * it gathered alone (tile_final.c): two tiles can run at once.  A run of
 * a 2-core machine's tiles one at a time keeps one core busy outside the
 * engine (gathering, the finality check, the output) and the engine's own
 * two threads do not scale fully either; two tiles at once keep both
 * cores busy throughout.  bounded.c starts the workers, each with a copy
 * of the run (bounded_int.h); they share what this file guards:
 *	memory	each tile run reserves its model's bytes (tdc_tp_tile_bytes
 *			of its points, and a file's rewrite in cell order its own)
 *			before it allocates them, and waits while the other's
 *			reservation leaves too little of the budget.  Requests are
 *			served in order of arrival, so neither worker starves.  No
 *			deadlock: a worker waits only while it holds nothing (a run
 *			releases its bytes before the next run's request; a rewrite
 *			in cell order happens while its tile holds nothing, in the
 *			counting pass of a rerun's gathering), every single request
 *			fits the budget (the runs check their sizes against it first),
 *			and a run that holds bytes finishes without waiting for any.
 *			So the sum of the runs' models stays within the budget, as
 *			one run's did.
 *	files	a rerun may rewrite a neighbour's file in cell order
 *			(bounded_cells.c) while the other worker reads it: a
 *			read-write lock per tile, and its `sorted` flag read and set
 *			under it.
 *	output	emit, trace and settle are called by one worker at a time;
 *			emit beside them when the caller's can take it
 *			(emit_concurrent: a raster's windows are per tile).
 *	tiles	claimed in the plan's order from a counter.  With two workers
 *			final tiles are emitted as they finish, not in the plan's
 *			order; only a caller that takes any order gets two
 *			(tdc_bounded_params.any_order).
 *	errors	the first worker to fail records its error and stops the
 *			other, which notices at its next poll (every few ms inside
 *			an engine run); the run returns the first error.
 * The engine of a run gets half the threads while both workers run, all
 * of them once the other has found no tile left.  A run's triangles do
 * not depend on its thread count, nor its finality verdict, so each tile
 * gives the same triangles whatever the number of workers.
 */
#include <pthread.h>
#include <stdlib.h>
#include <unistd.h>

#include "bounded_int.h"

/* How often a worker waiting for memory looks at the caller's cancel flag. */
#define WAIT_POLL_MS	10

struct bd_share
{
	pthread_mutex_t mu;			/* guards what follows, and cv */
	pthread_cond_t cv;
	int			nworkers,
				active,			/* workers still claiming tiles */
				threads,		/* the engine's threads for one tile at a time */
				next;			/* the next tile to claim */
	size_t		total,			/* the tiles' budget */
				free;			/* what no worker has reserved */
	uint64_t	ticket_next,	/* the next request's number */
				ticket_serve;	/* the request served next */
	int			stop;			/* set with the first error (read atomically) */
	bd_err		err;			/* that error */
	pthread_mutex_t out;		/* emit, trace, settle */
	pthread_rwlock_t *files;	/* per tile */
	int			nfiles;
};

static int
online_cpus(void)
{
	long		c = sysconf(_SC_NPROCESSORS_ONLN);

	return c < 1 ? 1 : (c > 256 ? 256 : (int) c);
}

/*
 * How many workers run the tiles of r: two when the caller takes any
 * order, the budget holds a second worker's scratch (bounded.c) and the
 * engine may use two threads or more, else one.
 */
int
tdc_bd_workers(const bounded_run *r)
{
	int			threads = r->p->opt->threads > 0 ? r->p->opt->threads : online_cpus();

	return r->two && threads >= 2 ? 2 : 1;
}

/*
 * The bytes a second worker holds beside its runs' model: its copies of
 * the per-cell scratch (states, added flags, the added list at its
 * largest), the hull cells, its extra boxes and bands' flags, and the
 * record buffers on its stack.
 */
size_t
tdc_bd_worker_bytes(const bounded_run *r)
{
	size_t		cells = (size_t) TDC_TP_GRID * TDC_TP_GRID;

	return cells * (1 + 1 + sizeof(uint32_t)) + sizeof(uint32_t) * TDC_TP_HULL_CELLS +
		(r->nhull + 1) * (32 + 1 + sizeof(double *)) + ((size_t) 512 << 10);
}

/* The share of r's tiles for nworkers workers; NULL when out of memory. */
struct bd_share *
tdc_bd_share_new(const bounded_run *r, int nworkers)
{
	struct bd_share *sh = calloc(1, sizeof(*sh));
	int			nt = r->nt > 0 ? r->nt : 1;

	if (sh == NULL)
		return NULL;
	sh->files = malloc(sizeof(pthread_rwlock_t) * nt);
	if (sh->files == NULL)
	{
		free(sh);
		return NULL;
	}
	pthread_mutex_init(&sh->mu, NULL);
	pthread_cond_init(&sh->cv, NULL);
	pthread_mutex_init(&sh->out, NULL);
	for (int t = 0; t < nt; t++)
		pthread_rwlock_init(&sh->files[t], NULL);
	sh->nfiles = nt;
	sh->nworkers = sh->active = nworkers;
	sh->threads = r->p->opt->threads > 0 ? r->p->opt->threads : online_cpus();
	sh->total = sh->free = r->budget;
	return sh;
}

void
tdc_bd_share_free(struct bd_share *sh)
{
	if (sh == NULL)
		return;
	for (int t = 0; t < sh->nfiles; t++)
		pthread_rwlock_destroy(&sh->files[t]);
	pthread_mutex_destroy(&sh->mu);
	pthread_cond_destroy(&sh->cv);
	pthread_mutex_destroy(&sh->out);
	free(sh->files);
	free(sh);
}

/* Has the caller canceled, or another worker failed? */
bool
tdc_bd_stopped(const bounded_run *r)
{
	return tdc_bd_canceled(r->p->cancel) ||
		(r->sh != NULL && __atomic_load_n(&r->sh->stop, __ATOMIC_RELAXED) != 0);
}

/*
 * The next tile for worker r, in the plan's order, or -1 when none is left
 * or the run stops (r->e set to the cancel when the caller canceled).
 */
int
tdc_bd_claim(bounded_run *r)
{
	struct bd_share *sh = r->sh;
	int			t = -1;

	if (tdc_bd_canceled(r->p->cancel))
	{
		tdc_bd_fail(&r->e, TDC_ECANCELED, "canceled");
		return -1;
	}
	pthread_mutex_lock(&sh->mu);
	if (!sh->stop && sh->next < r->nt)
		t = sh->next++;
	pthread_mutex_unlock(&sh->mu);
	return t;
}

/* Worker r claims no more tiles: the other's runs may take its threads. */
void
tdc_bd_leave(bounded_run *r)
{
	pthread_mutex_lock(&r->sh->mu);
	r->sh->active--;
	pthread_cond_broadcast(&r->sh->cv);
	pthread_mutex_unlock(&r->sh->mu);
}

/* Worker r failed with r->e: the first such error is the run's, and stops the others. */
void
tdc_bd_stop(bounded_run *r)
{
	struct bd_share *sh = r->sh;

	pthread_mutex_lock(&sh->mu);
	if (sh->err.code == TDC_OK)
		sh->err = r->e;
	__atomic_store_n(&sh->stop, 1, __ATOMIC_RELAXED);
	pthread_cond_broadcast(&sh->cv);
	pthread_mutex_unlock(&sh->mu);
}

/* The run's first error (TDC_OK when none), after the workers are joined. */
const bd_err *
tdc_bd_share_error(const struct bd_share *sh)
{
	return &sh->err;
}

/* The engine's threads for worker r's next run: a share while both work. */
void
tdc_bd_run_threads(bounded_run *r)
{
	struct bd_share *sh = r->sh;
	int			active;

	if (sh == NULL || sh->nworkers == 1)
		return;
	pthread_mutex_lock(&sh->mu);
	active = sh->active > 0 ? sh->active : 1;
	pthread_mutex_unlock(&sh->mu);
	r->wopt.threads = sh->threads / active > 0 ? sh->threads / active : 1;
}

/*
 * Reserve bytes of the budget for worker r (which holds nothing when it
 * must wait: see the top of this file), waiting while the other worker's
 * reservation leaves too little, in the order of the requests.  A request
 * above the whole budget waits for all of it (the callers check their
 * sizes against the budget first).  TDC_ECANCELED (r->e set) when the run
 * stops meanwhile.
 */
int
tdc_bd_reserve(bounded_run *r, size_t bytes)
{
	struct bd_share *sh = r->sh;
	uint64_t	mine;
	double		t0;

	if (sh == NULL || sh->nworkers == 1)
	{
		r->held += bytes;
		return TDC_OK;
	}
	if (bytes > sh->total)
		bytes = sh->total;
	t0 = now_s();
	pthread_mutex_lock(&sh->mu);
	mine = sh->ticket_next++;
	while (sh->ticket_serve != mine || sh->free < bytes)
	{
		struct timespec until;

		if (sh->stop || tdc_bd_canceled(r->p->cancel))
		{
			/* the run ends: the requests behind this one are woken to end too */
			__atomic_store_n(&sh->stop, 1, __ATOMIC_RELAXED);
			pthread_cond_broadcast(&sh->cv);
			pthread_mutex_unlock(&sh->mu);
			r->st->wait += now_s() - t0;
			return tdc_bd_fail(&r->e, TDC_ECANCELED, "canceled");
		}
		clock_gettime(CLOCK_REALTIME, &until);
		until.tv_nsec += WAIT_POLL_MS * 1000000L;
		if (until.tv_nsec >= 1000000000L)
		{
			until.tv_sec++;
			until.tv_nsec -= 1000000000L;
		}
		pthread_cond_timedwait(&sh->cv, &sh->mu, &until);
	}
	sh->free -= bytes;
	sh->ticket_serve++;
	pthread_cond_broadcast(&sh->cv);
	pthread_mutex_unlock(&sh->mu);
	r->held += bytes;
	r->st->wait += now_s() - t0;
	return TDC_OK;
}

/* Everything worker r reserved, given back. */
void
tdc_bd_release(bounded_run *r)
{
	struct bd_share *sh = r->sh;

	if (r->held == 0)
		return;
	if (sh != NULL && sh->nworkers > 1)
	{
		pthread_mutex_lock(&sh->mu);
		sh->free += r->held;
		pthread_cond_broadcast(&sh->cv);
		pthread_mutex_unlock(&sh->mu);
	}
	r->held = 0;
}

/* Tile s's files (and its sorted flag): read, or rewritten (write). */
void
tdc_bd_file_lock(const bounded_run *r, int s, bool write)
{
	if (r->sh == NULL)
		return;
	if (write)
		pthread_rwlock_wrlock(&r->sh->files[s]);
	else
		pthread_rwlock_rdlock(&r->sh->files[s]);
}

void
tdc_bd_file_unlock(const bounded_run *r, int s)
{
	if (r->sh != NULL)
		pthread_rwlock_unlock(&r->sh->files[s]);
}

/* The caller's callbacks, one worker at a time. */
void
tdc_bd_out_lock(const bounded_run *r)
{
	if (r->sh != NULL)
		pthread_mutex_lock(&r->sh->out);
}

void
tdc_bd_out_unlock(const bounded_run *r)
{
	if (r->sh != NULL)
		pthread_mutex_unlock(&r->sh->out);
}
