/*
 * run.c
 *		Running the core inside a backend: one job (or any work built on it,
 *		a Voronoi diagram, a constrained insertion) started, waited on while
 *		interrupts are watched, and freed; a core status as an ERROR with
 *		its SQLSTATE; the checks of the parameters every function shares.
 *
 * Waiting.  The core works on its own threads and never calls PostgreSQL;
 * the backend's main thread waits for it in slices of WAIT_SLICE_MS and
 * between slices looks at InterruptPending (tdc_wait_work, the one wait loop
 * of src/pg: every feature's work goes through it).  A query cancel,
 * statement_timeout or terminate request cancels the work, waits for its
 * threads to stop (they poll their cancel flag every few ms) and only then
 * lets CHECK_FOR_INTERRUPTS raise the error, so the error arrives within a
 * slice plus the workers' reaction time, and no thread outlives the
 * statement.  Other interrupts are processed while the work keeps running.
 * A PG_TRY around the loop stops the workers before the stack unwinds,
 * whatever ERROR leaves it.  A result value is written the same way: the
 * job's threads put the triangles at their offsets (tdc_job_emit_start)
 * while the main thread waits and watches.
 *
 * Ownership.  A job is malloc'd memory PostgreSQL knows nothing about.
 * Every job is owned by a TdcRun registered with a reset callback on the
 * memory context of the input buffer (the workers read the buffer until
 * they finish, so the job must go first): whatever ERROR is raised after
 * tdc_job_start, the context is reset during error recovery and the
 * callback cancels and joins the job and hands its memory to a detached
 * core thread to unmap, so the cancel does not wait for it.  On success
 * tdc_run_free frees the job (a big one on such a thread too) and clears
 * the pointer, so the callback has nothing left to do.
 *
 * Memory limit.  tdc_delaunay.max_memory (within the superuser's
 * tdc_delaunay.memory_ceiling) caps the collected vertices, the engine's
 * own estimate (tdc_estimate_memory) and an upper bound of the result; the
 * check happens before the engine allocates, and the engine gets what is
 * left as its own max_memory.
 *
 * docs/design/pg-runtime.md has the whole picture.
 */
#include "postgres.h"

#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <unistd.h>

#include "miscadmin.h"
#include "utils/memutils.h"

#include "tdc_pg.h"

/*
 * How long the backend waits for the core before it looks at
 * InterruptPending again: the most a cancel waits to be noticed, against
 * one wake-up per slice while the work runs.  10 ms is below what a user
 * notices.
 */
#define WAIT_SLICE_MS		10

/*
 * Runs on this many points or more keep their freed arrays for the next run
 * (mem_cache.c): below it the core's arrays come from malloc (its mapping
 * threshold is 256 kB, the mesh of some 3,600 points).
 */
#define KEEP_MIN_POINTS		4096

/*
 * What a successful run may leave to unmap in place, beyond what the cache
 * keeps (tdc_run_free): unmapping runs at some 7 ms per 64 MB on a quiet
 * machine, with no interrupt check.
 */
#define FREE_IN_PLACE_MAX	((uint64) 64 << 20)

/* ----------------------------------------------------------------
 *		status and waiting
 * ----------------------------------------------------------------
 */

static const char *
status_name(int rc)
{
	switch (rc)
	{
		case TDC_ENOMEM:
			return "out of memory";
		case TDC_ECANCELED:
			return "canceled";
		case TDC_EINVAL:
			return "invalid input";
		case TDC_ETOOBIG:
			return "input too large";
		case TDC_EMEMLIMIT:
			return "memory limit exceeded";
		case TDC_ETHREAD:
			return "could not start worker threads";
	}
	return "unknown error";
}

/* ERROR for a core status, with the core's message ("" or NULL: none). */
void
tdc_report_status(int rc, const char *msg, const char *fname)
{
	int			code;
	const char *hint = NULL;

	if (msg == NULL || msg[0] == '\0')
		msg = status_name(rc);

	switch (rc)
	{
		case TDC_ENOMEM:
			code = ERRCODE_OUT_OF_MEMORY;
			break;
		case TDC_EMEMLIMIT:
			code = ERRCODE_PROGRAM_LIMIT_EXCEEDED;
			hint = tdc_memory_limit_hint();
			break;
		case TDC_EINVAL:
			code = ERRCODE_INVALID_PARAMETER_VALUE;
			break;
		case TDC_ETOOBIG:
			code = ERRCODE_PROGRAM_LIMIT_EXCEEDED;
			break;
		case TDC_ECANCELED:
			code = ERRCODE_QUERY_CANCELED;
			break;
		case TDC_ETHREAD:
			code = ERRCODE_INSUFFICIENT_RESOURCES;
			hint = "Lower tdc_delaunay.threads.";
			break;
		default:
			code = ERRCODE_INTERNAL_ERROR;
			break;
	}
	ereport(ERROR,
			(errcode(code),
			 errmsg("%s: %s", fname, msg),
			 hint ? errhint("%s", hint) : 0));
	pg_unreachable();
}

/* Stop the work's threads and wait until none is left; its memory stays. */
static void
stop_work(void *work, const TdcWorkOps *ops)
{
	if (ops->cancel == NULL)
		return;					/* it cannot be stopped: left to finish alone */
	ops->cancel(work);
	(void) ops->wait(work, -1);
}

/*
 * Wait for work on the core's threads while watching for interrupts (see
 * the top of this file); returns its final status, never TDC_RUNNING.  A
 * cancel or terminate is an ERROR once the work's threads have stopped.
 */
int
tdc_wait_work(void *work, const TdcWorkOps *ops, const char *fname)
{
	int			rc;

	/*
	 * Work that ran inline is finished already: no loop, and no PG_TRY (a
	 * sigsetjmp per phase).
	 */
	rc = ops->wait(work, 0);
	if (rc != TDC_RUNNING)
		return rc;

	PG_TRY();
	{
		while ((rc = ops->wait(work, WAIT_SLICE_MS)) == TDC_RUNNING)
		{
			if (!InterruptPending)
				continue;
			if (QueryCancelPending || ProcDiePending)
			{
				stop_work(work, ops);
				CHECK_FOR_INTERRUPTS();
				/* interrupts are held off: still, there is no result */
				ereport(ERROR,
						(errcode(ERRCODE_QUERY_CANCELED),
						 errmsg("%s: %s canceled", fname, ops->what)));
			}
			/* anything else: process it, the work goes on */
			CHECK_FOR_INTERRUPTS();
		}
	}
	PG_CATCH();
	{
		stop_work(work, ops);
		PG_RE_THROW();
	}
	PG_END_TRY();
	return rc;
}

TDC_WORK_OPS(job_ops, tdc_job, tdc_job, "triangulation");

/*
 * Wait for *workp as tdc_wait_work does; returns when it succeeded.  On a
 * failure the work is freed (*workp set to NULL) and the ERROR carries its
 * message.
 */
void
tdc_finish_work(void **workp, const TdcWorkOps *ops, const char *fname)
{
	char		err[256];
	int			rc = tdc_wait_work(*workp, ops, fname);

	if (rc != TDC_OK)
	{
		snprintf(err, sizeof(err), "%s", ops->error(*workp));
		ops->free(*workp);
		*workp = NULL;
		tdc_report_status(rc, err, fname);
	}
}

/*
 * Wait for the job's current phase (the triangulation, or the hand-over of
 * its triangles).  Returns when it succeeded; any failure is an ERROR.
 */
static void
wait_for_job(TdcRun *run, const char *fname)
{
	tdc_finish_work((void **) &run->job, &job_ops, fname);
}

/* A run and the callback that frees its job on an error: one allocation. */
typedef struct RunAlloc
{
	TdcRun		run;
	MemoryContextCallback cb;
} RunAlloc;

static void
run_reset_callback(void *arg)
{
	TdcRun	   *run = (TdcRun *) arg;

	/* only errors and cancels get here: the client is waiting */
	if (run->job != NULL)
	{
		tdc_job_free_background(run->job);
		run->job = NULL;
		/* after the arrays of any object built on the job (freed first) */
		tdc_backend_cache_release();
	}
}

int
tdc_effective_threads(void)
{
	/* sysconf reads /sys on every call: once per backend is enough */
	static int	cpus = 0;
	int			ceiling,
				t;

	if (cpus == 0)
	{
		long		ncpu = sysconf(_SC_NPROCESSORS_ONLN);

		cpus = ncpu > 0 ? (int) Min(ncpu, 1024) : 1;
	}
	ceiling = tdc_guc_max_threads > 0 ? tdc_guc_max_threads : cpus;
	t = tdc_guc_threads > 0 ? tdc_guc_threads : cpus;
	return Min(t, ceiling);
}

/* The figures of a finished job for the stats NOTICE, kept past its free. */
void
tdc_stats_take(const tdc_job *job, TdcRunStats *st)
{
	st->input = tdc_num_input(job);
	st->sites = tdc_num_sites(job);
	st->triangles = tdc_num_triangles(job);
	st->edges = tdc_num_edges(job);
	st->threads = tdc_threads_used(job);
	st->levels = tdc_levels_used(job);
	st->grid = tdc_grid_used(job);
	tdc_job_times(job, &st->t);
}

/*
 * The stats NOTICE.  phases: more figures, measured outside the core
 * (reading, writing, freeing), appended to the DETAIL; "" for none.
 */
void
tdc_stats_report(const TdcRunStats *st, const char *fname, const char *phases)
{
	ereport(NOTICE,
			(errmsg("%s: %zu input points, %zu sites, %zu triangles, %zu edges",
					fname, st->input, st->sites, st->triangles, st->edges),
			 errdetail("threads %d, levels %d, grid %d; sort %.3f ms, subdivide %.3f ms, leaves %.3f ms, merge %.3f ms, total %.3f ms%s",
					   st->threads, st->levels, st->grid,
					   st->t.sort * 1000.0, st->t.subdivide * 1000.0,
					   st->t.leaves * 1000.0, st->t.merge * 1000.0,
					   st->t.total * 1000.0, phases)));
}

/* Milliseconds since "start" (set with INSTR_TIME_SET_CURRENT). */
double
tdc_ms_since(instr_time start)
{
	instr_time	now;

	INSTR_TIME_SET_CURRENT(now);
	INSTR_TIME_SUBTRACT(now, start);
	return INSTR_TIME_GET_MILLISEC(now);
}

/* ----------------------------------------------------------------
 *		parameters
 * ----------------------------------------------------------------
 */

/* ERROR unless flags is an output kind of the function: see tdc_flags_valid. */
void
tdc_check_flags(int flags, bool constraints, const char *fname)
{
	if (!tdc_flags_valid(flags, constraints))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: invalid flags %d", fname, flags),
				 errhint("Use 0 for a GEOMETRYCOLLECTION of polygons, 1 for a MULTILINESTRING of edges, "
						 "2 for a TIN%s.",
						 constraints ? ", 5 for a MULTILINESTRING of the constraint edges alone" : "")));
}

/* ERROR unless tolerance is a finite number >= 0 (NULL: isnull). */
void
tdc_check_tolerance(bool isnull, double tolerance, const char *fname)
{
	if (isnull || !(tolerance >= 0) || isinf(tolerance))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: tolerance must be a finite number >= 0, not %s", fname,
						isnull ? "NULL" : psprintf("%g", tolerance))));
}

void
tdc_check_params(double tolerance, int flags, const char *fname)
{
	tdc_check_tolerance(false, tolerance, fname);
	tdc_check_flags(flags, false, fname);
}

/* ----------------------------------------------------------------
 *		a run: one job from start to free
 * ----------------------------------------------------------------
 */

/* The engine's options from the session's settings (threads, grid, levels). */
void
tdc_session_options(tdc_options *opt)
{
	tdc_options_init(opt);
	opt->threads = tdc_effective_threads();
	opt->grid_size = tdc_guc_grid_size;
	opt->levels = tdc_guc_levels;
}

/*
 * The options of a run on buf: the session's settings and the memory limit.
 * *room: what the limit leaves over once the run and its result are counted.
 */
static void
run_options(const TdcPointBuf *buf, double tolerance, uint64 result_bytes,
			const char *fname, tdc_options *opt, uint64 *room)
{
	uint64		limit = tdc_max_memory_bytes();

	tdc_session_options(opt);
	opt->tolerance = tolerance;
	opt->times = tdc_guc_stats;
	if (limit > 0)
	{
		/* the same figure for every caller; the result value apart */
		uint64		run_bytes = tdc_pointbuf_bytes(buf) +
			tdc_estimate_memory((size_t) buf->n, opt);

		if (run_bytes + result_bytes > limit)
			tdc_report_memory_limit(fname,
									psprintf("triangulating %llu vertices",
											 (unsigned long long) buf->n),
									run_bytes, result_bytes);
		opt->max_memory = (size_t) (limit - tdc_pointbuf_bytes(buf) - result_bytes);
		*room = limit - run_bytes - result_bytes;
	}
	else
		*room = PG_UINT64_MAX;
}

/*
 * The tdc_delaunay.max_memory check of tdc_run, for a caller that needs
 * memory of its own before it runs (less than the run's) and must fail
 * before taking it.
 */
void
tdc_check_run_memory(const TdcPointBuf *buf, double tolerance,
					 uint64 result_bytes, const char *fname)
{
	tdc_options opt;
	uint64		room;

	run_options(buf, tolerance, result_bytes, fname, &opt, &room);
}

/*
 * Triangulate the points of buf with the core, waiting interruptibly.
 * result_bytes: what the caller will allocate for the result, for the
 * tdc_delaunay.max_memory check.  Returns with run->job finished (TDC_OK);
 * any failure is an ERROR.  The caller calls tdc_run_free when done.
 */
TdcRun *
tdc_run(const TdcPointBuf *buf, double tolerance, uint64 result_bytes,
		const char *fname)
{
	tdc_options opt;
	uint64		room;
	TdcRun	   *run;
	RunAlloc   *ra;
	char		err[256];
	int			rc;

	run_options(buf, tolerance, result_bytes, fname, &opt, &room);

	/* both live as long as the context they are registered with */
	ra = MemoryContextAllocZero(buf->cxt, sizeof(RunAlloc));
	run = &ra->run;

	/*
	 * Arrays kept from earlier runs, within what max_memory leaves over.  A
	 * run on fewer than KEEP_MIN_POINTS points has its arrays from malloc,
	 * nothing to keep, and the release timeout's two system calls would be
	 * a tenth of a call on a few points: it only gives back what its limit
	 * needs.
	 */
	run->kept = buf->n >= KEEP_MIN_POINTS;
	run->engine_bytes = tdc_estimate_memory((size_t) buf->n, &opt);
	opt.cache = tdc_backend_cache(room, run->kept);
	ra->cb.func = run_reset_callback;
	ra->cb.arg = run;
	/* on the buffer's context: it must not be freed before the job is */
	MemoryContextRegisterResetCallback(buf->cxt, &ra->cb);

	err[0] = '\0';
	rc = tdc_job_start(buf->xy, (size_t) buf->n, &opt, &run->job, err,
					   sizeof(err));
	if (rc != TDC_OK)
	{
		run->job = NULL;
		tdc_report_status(rc, err, fname);
	}
	wait_for_job(run, fname);
	return run;
}

/*
 * Hand the finished job's triangles to emit on the core's threads (the
 * result is written in parallel), waiting as for the triangulation.
 * Returns false, with nothing emitted, when no thread could be started:
 * the caller then writes on its own.
 */
bool
tdc_run_emit(TdcRun *run, tdc_emit_fn emit, void *arg, const char *fname)
{
	char		err[256];
	int			rc;

	rc = tdc_job_emit_start(run->job, emit, arg, err, sizeof(err));
	if (rc == TDC_ETHREAD)
		return false;
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	wait_for_job(run, fname);
	return true;
}

/*
 * Free a successful run's job.  In place, its arrays go to the backend's
 * cache (up to tdc_delaunay.keep_memory) for the next run and the rest is
 * unmapped, so no thread outlives the statement.  But unmapping takes time
 * in proportion to the size and cannot be interrupted: at 5 million points
 * (a 600 MB job) some 150 ms on a quiet machine, during which a
 * statement_timeout or cancel waited while the result was handed back.
 * So a job that would leave more than FREE_IN_PLACE_MAX to unmap goes to a
 * detached core thread instead, as a failed one does (the cache then keeps
 * none of it), and the statement ends at once.  Pending interrupts are the
 * caller's to process before.
 */
void
tdc_run_free(TdcRun *run)
{
	if (run->job != NULL)
	{
		uint64		keep = run->kept ? (uint64) tdc_guc_keep_memory_mb << 20 : 0;

		if (run->engine_bytes > keep + FREE_IN_PLACE_MAX)
			tdc_job_free_background(run->job);
		else
			tdc_job_free(run->job);
		run->job = NULL;
	}
	if (run->kept)
		tdc_backend_cache_idle();
	run->kept = false;
}
