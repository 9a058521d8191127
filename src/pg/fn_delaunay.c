/*
 * tdc_funcs.c
 *		ST_TDCDelaunayTriangles, ST_TDCDelaunayDump and the helper that runs
 *		the core inside a backend.
 *
 * Running the core.  The core triangulates on its own worker threads and
 * never calls PostgreSQL; the backend's main thread waits for it in slices of
 * WAIT_SLICE_MS (tdc_job_wait with a timeout) and between slices looks at
 * InterruptPending.  A query cancel, statement_timeout or terminate request
 * cancels the job, waits for the workers to stop (they poll their cancel
 * flag every few ms) and only then lets CHECK_FOR_INTERRUPTS raise the
 * error, so the error arrives within a slice plus the workers' reaction
 * time, and no thread outlives the statement.  Other interrupts are
 * processed while the job keeps running.  A result value is written the
 * same way: the job's threads put the triangles at their offsets
 * (tdc_job_emit_start) while the main thread waits and watches.
 *
 * The job is malloc'd memory that PostgreSQL knows nothing about.  Every job
 * is owned by a TdcRun registered with a reset callback on the memory context
 * of the input buffer (the workers read the buffer until they finish, so the
 * job must go first): whatever ERROR is raised after tdc_job_start (a cancel,
 * out of memory while building the result, an error in a later row...), the
 * context is reset during error recovery and the callback cancels and joins
 * the job and hands its memory to a detached core thread to unmap.  The
 * client sees the error only once the transaction is aborted (psql waits for
 * ReadyForQuery), and unmapping a big job takes time in proportion to its
 * size, so the cancel does not wait for it.  While the job runs, a PG_TRY around the wait loop stops
 * the workers at once, before the stack unwinds.  On success tdc_run_free
 * frees the job in place (no thread outlives a successful statement) and
 * clears the pointer, so the callback has nothing left to do.  Pending
 * interrupts are processed before that free.
 *
 * Memory limit.  tdc_delaunay.max_memory (within the superuser's
 * tdc_delaunay.memory_ceiling) caps the collected vertices, the
 * engine's own estimate (tdc_estimate_memory) and an upper bound of the
 * result; the check happens before the engine allocates, and the engine
 * gets what is left as its own max_memory.
 *
 * Reading a big value.  ST_TDCDelaunayTriangles gets its argument as a
 * TOAST pointer when the value is stored out of line (any value over about
 * 2 kB unless it compresses below that; a collection of 5 million points is
 * 120 MB, about 90 MB with pglz).  Detoasting it (PG_DETOAST_DATUM) would
 * fetch all its chunks into one buffer, decompress it into a second, and
 * only then let the walker copy the vertices into a third, all without an
 * interrupt check: a cancel arriving then would wait for the whole read.
 * Instead the stored bytes are fetched a slice at a
 * time (table_relation_fetch_toast_slice, 128 chunks, about 250 kB), and
 * handed to the walker (gserialized.c) as they come; compressed bytes,
 * stored out of line or in line, are decompressed a piece at a time into a
 * window that keeps the last 4 kB (pglz) or 64 kB (lz4) of output, which is
 * as far back as either format refers.  PostgreSQL offers no incremental
 * decompression (its slice functions decompress from the start each time),
 * so both formats are decoded here, with every length and offset checked
 * against the input left, the output produced and the raw size announced:
 * corrupt data is an ERROR, never a read or write outside the buffers.
 * Interrupts are checked before every slice and piece (a few ms of work).
 * Other values (in line and uncompressed, or an expanded or indirect datum,
 * or compressed with a method this code does not know) are detoasted as
 * before.  An ERROR raised while reading carries a CONTEXT line saying how
 * the value was stored.
 *
 * ST_TDCDelaunayDump collects the vertices of its query's single geometry
 * column (tdc_dump_query.c), triangulates, and returns one POLYGON row per
 * triangle through a tuplestore, which spills to disk past work_mem.  So it
 * is not bound by the 1 GB limit of a single value.
 */
#include "postgres.h"

#include <math.h>
#include <unistd.h>

#include "access/detoast.h"
#include "access/heaptoast.h"
#include "access/table.h"
#include "access/tableam.h"
#include "access/toast_compression.h"
#include "funcapi.h"
#include "miscadmin.h"
#include "portability/instr_time.h"
#include "utils/builtins.h"
#include "utils/memutils.h"
#include "utils/tuplestore.h"

#include "tdc_pg.h"

/*
 * How long the backend waits for a job before it looks at InterruptPending
 * again: the most a cancel waits to be noticed, against one wake-up per
 * slice while the job runs.  10 ms is below what a user notices.
 */
#define WAIT_SLICE_MS		10

/*
 * Runs on this many points or more keep their freed arrays for the next run
 * (tdc_cache.c): below it the core's arrays come from malloc (its mapping
 * threshold is 256 kB, the mesh of some 3,600 points).
 */
#define KEEP_MIN_POINTS		4096

/*
 * Dump rows put into the tuplestore between two interrupt checks: a row is
 * a small POLYGON value, and once the tuplestore spills to disk each costs
 * a write, so 65536 rows are some ms of work.  A power of two.
 */
#define DUMP_POLL_ROWS		65536

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

/* ereport a core status with the core's message. */
static void
report_core_error(int rc, const char *msg, const char *fname)
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
}

/* Cancel the workers and wait until none is left; the memory stays. */
static void
stop_job(TdcRun *run)
{
	tdc_job_cancel(run->job);
	(void) tdc_job_wait(run->job, -1);
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

static int
effective_threads(void)
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

/* What the stats NOTICE reports of a finished job, kept past its free. */
typedef struct RunStats
{
	size_t		input;
	size_t		sites;
	size_t		triangles;
	size_t		edges;
	int			threads;
	int			levels;
	int			grid;
	tdc_times	t;
} RunStats;

static void
stats_take(const tdc_job *job, RunStats *st)
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
static void
stats_report(const RunStats *st, const char *fname, const char *phases)
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
static double
ms_since(instr_time start)
{
	instr_time	now;

	INSTR_TIME_SET_CURRENT(now);
	INSTR_TIME_SUBTRACT(now, start);
	return INSTR_TIME_GET_MILLISEC(now);
}

/*
 * Wait for the job's current phase (the triangulation, or the hand-over of
 * its triangles) while watching for interrupts.  Returns when it succeeded;
 * any failure, cancel included, is an ERROR after the workers stopped.
 */
static void
wait_for_job(TdcRun *run, const char *fname)
{
	char		err[256];
	int			rc;

	/*
	 * A small job ran inline and is finished already: no loop, and no
	 * PG_TRY (a sigsetjmp per phase).
	 */
	rc = tdc_job_wait(run->job, 0);

	/*
	 * The workers read the input buffer (and may write the result) until
	 * they finish: whatever ERROR leaves this loop, stop them before the
	 * stack unwinds.  Freeing is left to the reset callback, which runs
	 * after the error went to the client.
	 */
	if (rc == TDC_RUNNING)
	{
		PG_TRY();
		{
			while ((rc = tdc_job_wait(run->job, WAIT_SLICE_MS)) == TDC_RUNNING)
			{
				if (!InterruptPending)
					continue;
				if (QueryCancelPending || ProcDiePending)
				{
					stop_job(run);
					CHECK_FOR_INTERRUPTS();
					/* interrupts are held off: still, we have no result */
					ereport(ERROR,
							(errcode(ERRCODE_QUERY_CANCELED),
							 errmsg("%s: triangulation canceled", fname)));
				}
				/* anything else: process it, the job keeps running */
				CHECK_FOR_INTERRUPTS();
			}
		}
		PG_CATCH();
		{
			if (run->job != NULL)
				stop_job(run);
			PG_RE_THROW();
		}
		PG_END_TRY();
	}

	if (rc != TDC_OK)
	{
		snprintf(err, sizeof(err), "%s", tdc_job_error(run->job));
		tdc_job_free(run->job);
		run->job = NULL;
		report_core_error(rc, err, fname);
	}
}

/* ----------------------------------------------------------------
 *		shared helpers
 * ----------------------------------------------------------------
 */

void
tdc_check_params(double tolerance, int flags, const char *fname)
{
	if (isnan(tolerance) || tolerance < 0 || isinf(tolerance))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: tolerance must be a finite number >= 0, not %g",
						fname, tolerance)));
	if (flags < TDC_OUT_POLYGONS || flags > TDC_OUT_TIN)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: invalid flags %d", fname, flags),
				 errhint("Use 0 for a GEOMETRYCOLLECTION of polygons, 1 for a MULTILINESTRING of edges, 2 for a TIN.")));
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

	tdc_options_init(opt);
	opt->threads = effective_threads();
	opt->grid_size = tdc_guc_grid_size;
	opt->levels = tdc_guc_levels;
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
		report_core_error(rc, err, fname);
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
		report_core_error(rc, err, fname);
	wait_for_job(run, fname);
	return true;
}

void
tdc_run_free(TdcRun *run)
{
	if (run->job != NULL)
	{
		tdc_job_free(run->job);
		run->job = NULL;
	}
	if (run->kept)
		tdc_backend_cache_idle();
	run->kept = false;
}

/*
 * Triangulate buf into one geometry value of the given kind.  read_ms: how
 * long reading the input took, for the stats (< 0: not known).
 */
static Datum
triangulate_to_datum(const TdcPointBuf *buf, double tolerance, int flags,
					 const char *fname, double read_ms)
{
	TdcRun	   *run;
	struct varlena *result;
	TdcGserWriter w;
	RunStats	st;
	instr_time	start;
	double		write_ms = 0;

	if (buf->n == 0)
		return PointerGetDatum(tdc_gser_empty(flags, buf->srid));

	run = tdc_run(buf, tolerance,
				  tdc_gser_result_bound(buf->n, flags, buf->hasz), fname);
	if (tdc_guc_stats)
	{
		stats_take(run->job, &st);
		INSTR_TIME_SET_CURRENT(start);
	}
	result = tdc_gser_result_alloc(run->job, flags, buf, fname, &w);

	/*
	 * A job that ran inline would hand its triangles over on this thread
	 * too, in the same order (so the same bytes): writing them directly
	 * spares the phase's set-up and its wait, which a call on a few points
	 * feels.
	 */
	if (flags == TDC_OUT_EDGES || w.count == 0 || buf->n < TDC_INLINE_MAX ||
		!tdc_run_emit(run, tdc_gser_emit, &w, fname))
		tdc_gser_fill(&w);
	/* freeing a big job takes a while: let a pending cancel in first */
	CHECK_FOR_INTERRUPTS();
	if (tdc_guc_stats)
	{
		write_ms = ms_since(start);
		INSTR_TIME_SET_CURRENT(start);
	}
	tdc_run_free(run);
	if (tdc_guc_stats)
	{
		char		phases[160];
		char		read[40] = "";
		double		free_ms = ms_since(start);

		if (read_ms >= 0)
			snprintf(read, sizeof(read), "read %.3f ms, ", read_ms);
		/* kept: what the next run may take back (tdc_cache.c) */
		snprintf(phases, sizeof(phases), "; %swrite %.3f ms, free %.3f ms, kept %llu kB",
				 read, write_ms, free_ms, tdc_backend_cache_kept_kb());
		stats_report(&st, fname, phases);
	}
	return PointerGetDatum(result);
}

/* Triangulate buf into one geometry value of the given kind. */
Datum
tdc_triangulate_to_datum(const TdcPointBuf *buf, double tolerance, int flags,
						 const char *fname)
{
	return triangulate_to_datum(buf, tolerance, flags, fname, -1);
}

/* ----------------------------------------------------------------
 *		reading big values
 * ----------------------------------------------------------------
 */

/* Stored bytes fetched at a time: whole TOAST chunks, about 250 kB. */
#define SLICE_BYTES			(128 * TOAST_MAX_CHUNK_SIZE)
/* Decompressed bytes handed to the walker at a time. */
#define PIECE_BYTES			((Size) 256 * 1024)
/* Decompressed bytes kept for back-references: pglz's reach 4095 bytes. */
#define PGLZ_HISTORY		((Size) 4096)
/* lz4's reach 65535 bytes. */
#define LZ4_HISTORY			((Size) 65536)
/* A pglz group: a control byte and 8 items of at most 3 bytes... */
#define PGLZ_GROUP_IN		25
/* ...giving at most 8 matches of 273 bytes. */
#define PGLZ_GROUP_OUT		(8 * 273)

/* Where a lz4 decoder stopped: in which part of which sequence. */
typedef enum Lz4Step
{
	LZ4_TOKEN,					/* at a sequence's token */
	LZ4_LITLEN,					/* adding up literal length bytes */
	LZ4_LITERALS,				/* copying literals */
	LZ4_OFFSET,					/* at the match offset */
	LZ4_MATCHLEN,				/* adding up match length bytes */
	LZ4_MATCH,					/* copying the match */
	LZ4_END						/* the block ended after its last literals */
} Lz4Step;

/*
 * A TOASTed value read front to back.  The stored bytes (compressed or not)
 * come from the TOAST table a slice at a time, or, for a value compressed
 * in line, from memory; compressed bytes are decompressed a piece at a
 * time into a window that keeps the last bytes for back-references.
 */
typedef struct ToastReader
{
	TdcGserSource src;			/* first: what the walker sees */
	const char *fname;
	int			method;			/* -1: not compressed, else a ToastCompressionId */

	/* stored bytes */
	Relation	toastrel;		/* NULL: all in memory, "in" .. "in_end" */
	Oid			valueid;
	int32		stored;			/* bytes stored */
	int32		fetched;		/* bytes fetched so far */
	struct varlena *slice;		/* fetch buffer of SLICE_BYTES */
	char	   *inbuf;			/* compressed: a few bytes kept + one slice */
	const uint8 *in;			/* compressed bytes not decoded yet */
	const uint8 *in_end;

	/* decompressed bytes */
	uint8	   *out;			/* history + PIECE_BYTES */
	Size		history;		/* bytes kept for back-references */
	Size		out_pos;		/* bytes of out in use */
	uint64		produced;		/* bytes decompressed so far */
	uint64		rawsize;		/* bytes the value decompresses to */

	/* lz4: where the current sequence is */
	Lz4Step		step;
	uint64		len;			/* literal or match bytes left */
	uint32		off;			/* match offset */
	int			matchnib;		/* match length field of the token */
} ToastReader;

static void
toast_corrupt(const ToastReader *r)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: compressed %s data is corrupt", r->fname,
					r->method == TOAST_LZ4_COMPRESSION_ID ? "lz4" : "pglz")));
}

/* Fetch the next slice of stored bytes into r->slice; returns its length. */
static Size
fetch_slice(ToastReader *r)
{
	int32		n = Min(r->stored - r->fetched, (int32) SLICE_BYTES);

	CHECK_FOR_INTERRUPTS();
	table_relation_fetch_toast_slice(r->toastrel, r->valueid, r->stored,
									 r->fetched, n, r->slice);
	r->fetched += n;
	return (Size) n;
}

/*
 * Make at least "want" compressed bytes available at r->in, fetching a
 * slice when fewer remain; returns false when fewer than that are left in
 * the whole value.  The bytes not decoded yet (fewer than "want") move to
 * the front of the input buffer, and the slice goes after them.
 */
static bool
toast_input(ToastReader *r, Size want)
{
	Size		keep = r->in_end - r->in;
	Size		n;

	if (keep >= want)
		return true;
	if (r->toastrel == NULL || r->fetched == r->stored)
		return false;
	memmove(r->inbuf, r->in, keep);
	n = fetch_slice(r);
	memcpy(r->inbuf + keep, VARDATA(r->slice), n);
	r->in = (const uint8 *) r->inbuf;
	r->in_end = r->in + keep + n;
	return keep + n >= want;
}

/*
 * Copy a match of len bytes from off bytes back.  They may overlap: the
 * match then repeats the last off bytes, and each copy doubles what can be
 * copied in one go (the distance from the source grows, the source stays).
 */
static inline void
copy_match(uint8 *dst, Size off, Size len)
{
	const uint8 *src = dst - off;

	while (len > 0)
	{
		Size		k = Min(len, (Size) (dst - src));

		memcpy(dst, src, k);
		dst += k;
		len -= k;
	}
}

/*
 * Decompress pglz groups into out from r->out_pos up to "limit".  The format
 * (common/pg_lzcompress.c): a control byte, then 8 items, each a literal
 * byte (bit clear, low bit first) or a match (bit set): 2 bytes, length - 3
 * in the low nibble of the first, a 12-bit offset in its high nibble and the
 * second, and when the length field is 15 a third byte adds to the length.
 * The value's stream ends with its input: then exactly rawsize bytes must
 * have been produced.
 */
static void
pglz_piece(ToastReader *r, Size limit)
{
	uint8	   *out = r->out;
	Size		pos = r->out_pos;
	uint64		base = r->produced - pos;	/* produced = base + pos */

	while (limit - pos >= PGLZ_GROUP_OUT)
	{
		const uint8 *in;
		const uint8 *end;
		uint8		ctrl;

		if (!toast_input(r, PGLZ_GROUP_IN) && r->in == r->in_end)
			break;				/* all input decoded */
		in = r->in;
		end = r->in_end;
		ctrl = *in++;
		for (int bit = 0; bit < 8 && in < end; bit++, ctrl >>= 1)
		{
			if (ctrl & 1)
			{
				Size		len;
				Size		off;

				if (end - in < 2)
					toast_corrupt(r);
				len = (in[0] & 0x0f) + 3;
				off = ((Size) (in[0] & 0xf0) << 4) | in[1];
				in += 2;
				if (len == 18)
				{
					if (in == end)
						toast_corrupt(r);
					len += *in++;
				}
				if (off == 0 || off > base + pos ||
					len > r->rawsize - (base + pos))
					toast_corrupt(r);
				copy_match(out + pos, off, len);
				pos += len;
			}
			else
			{
				if (base + pos >= r->rawsize)
					toast_corrupt(r);
				out[pos++] = *in++;
			}
		}
		r->in = in;
	}
	r->produced = base + pos;
	r->out_pos = pos;
}

/*
 * Decompress lz4 into out from r->out_pos up to "limit", resuming wherever
 * the previous call stopped.  The format (one lz4 block): sequences of a
 * token (literal length in the high nibble, match length - 4 in the low
 * one, 15 meaning that bytes follow, each added, until one is not 255), the
 * literals, a 2-byte little-endian offset and the match; the last sequence
 * stops after its literals, at the end of the input.
 */
static void
lz4_piece(ToastReader *r, Size limit)
{
	uint8	   *out = r->out;
	Size		pos = r->out_pos;
	uint64		base = r->produced - pos;
	Size		k;
	uint8		b;

	while (pos < limit)
	{
		switch (r->step)
		{
			case LZ4_TOKEN:
				if (!toast_input(r, 1))
					toast_corrupt(r);
				b = *r->in++;
				r->len = b >> 4;
				r->matchnib = b & 0x0f;
				r->step = r->len == 15 ? LZ4_LITLEN : LZ4_LITERALS;
				break;

			case LZ4_LITLEN:
			case LZ4_MATCHLEN:
				if (!toast_input(r, 1))
					toast_corrupt(r);
				b = *r->in++;
				r->len += b;
				if (r->len > r->rawsize)
					toast_corrupt(r);
				if (b != 255)
					r->step = r->step == LZ4_LITLEN ? LZ4_LITERALS : LZ4_MATCH;
				break;

			case LZ4_LITERALS:
				if (r->len > r->rawsize - (base + pos))
					toast_corrupt(r);
				if (r->len > 0 && !toast_input(r, 1))
					toast_corrupt(r);
				k = Min(Min(r->len, (uint64) (limit - pos)),
						(uint64) (r->in_end - r->in));
				memcpy(out + pos, r->in, k);
				pos += k;
				r->in += k;
				r->len -= k;
				if (r->len == 0)
				{
					/* the last sequence: no offset follows */
					if (!toast_input(r, 1))
					{
						r->step = LZ4_END;
						goto done;
					}
					r->step = LZ4_OFFSET;
				}
				break;

			case LZ4_OFFSET:
				if (!toast_input(r, 2))
					toast_corrupt(r);
				r->off = r->in[0] | ((uint32) r->in[1] << 8);
				r->in += 2;
				if (r->off == 0 || r->off > base + pos)
					toast_corrupt(r);
				r->len = r->matchnib + 4;
				r->step = r->matchnib == 15 ? LZ4_MATCHLEN : LZ4_MATCH;
				break;

			case LZ4_MATCH:
				if (r->len > r->rawsize - (base + pos))
					toast_corrupt(r);
				k = Min(r->len, (uint64) (limit - pos));
				copy_match(out + pos, r->off, k);
				pos += k;
				r->len -= k;
				if (r->len == 0)
					r->step = LZ4_TOKEN;
				break;

			case LZ4_END:
				goto done;
		}
	}
done:
	r->produced = base + pos;
	r->out_pos = pos;
}

/* TdcGserSource.next of an uncompressed value: its next slice. */
static bool
plain_next(TdcGserSource *src, const char **data, Size *len)
{
	ToastReader *r = (ToastReader *) src;

	if (r->fetched == r->stored)
		return false;
	*len = fetch_slice(r);
	*data = VARDATA(r->slice);
	return true;
}

/* TdcGserSource.next of a compressed value: the next piece decompressed. */
static bool
compressed_next(TdcGserSource *src, const char **data, Size *len)
{
	ToastReader *r = (ToastReader *) src;
	Size		start;

	if (r->produced == r->rawsize)
		return false;
	CHECK_FOR_INTERRUPTS();
	/* keep the history, drop what is older: the walker is done with it */
	if (r->out_pos > r->history)
	{
		memmove(r->out, r->out + r->out_pos - r->history, r->history);
		r->out_pos = r->history;
	}
	start = r->out_pos;
	if (r->method == TOAST_PGLZ_COMPRESSION_ID)
		pglz_piece(r, start + PIECE_BYTES);
	else
		lz4_piece(r, start + PIECE_BYTES);
	if (r->out_pos == start)
		toast_corrupt(r);		/* the input ended early */
	*data = (const char *) r->out + start;
	*len = r->out_pos - start;
	return true;
}

/* CONTEXT of an ERROR (a cancel included) raised while reading a value. */
static void
toast_read_context(void *arg)
{
	const ToastReader *r = arg;
	const char *method = r->method == TOAST_LZ4_COMPRESSION_ID ? "lz4" : "pglz";

	if (r->toastrel != NULL && r->method == -1)
		errcontext("reading a geometry value of %llu bytes stored out of line",
				   (unsigned long long) r->rawsize);
	else if (r->toastrel != NULL)
		errcontext("reading a geometry value of %llu bytes stored out of line, compressed with %s",
				   (unsigned long long) r->rawsize, method);
	else
		errcontext("reading a geometry value of %llu bytes compressed with %s",
				   (unsigned long long) r->rawsize, method);
}

/*
 * Read a value stored out of line or compressed into buf, a slice at a time
 * (see the top of this file); returns false, having read nothing, for any
 * other value, which the caller detoasts as usual.
 */
static bool
read_toasted_value(TdcPointBuf *buf, struct varlena *attr, const char *fname)
{
	ToastReader r;
	ErrorContextCallback errcb;

	/* the common case, a small value in line: nothing to do here */
	if (!VARATT_IS_EXTERNAL_ONDISK(attr) && !VARATT_IS_COMPRESSED(attr))
		return false;
	memset(&r, 0, sizeof(r));
	r.fname = fname;
	if (VARATT_IS_EXTERNAL_ONDISK(attr))
	{
		struct varatt_external ptr;

		VARATT_EXTERNAL_GET_POINTER(ptr, attr);
		r.stored = VARATT_EXTERNAL_GET_EXTSIZE(ptr);
		r.rawsize = ptr.va_rawsize - VARHDRSZ;
		r.method = VARATT_EXTERNAL_IS_COMPRESSED(ptr) ?
			(int) VARATT_EXTERNAL_GET_COMPRESS_METHOD(ptr) : -1;
		r.valueid = ptr.va_valueid;
		if (r.method != -1 && r.method != TOAST_PGLZ_COMPRESSION_ID &&
			r.method != TOAST_LZ4_COMPRESSION_ID)
			return false;
		r.toastrel = table_open(ptr.va_toastrelid, AccessShareLock);
		r.slice = palloc(VARHDRSZ + Min(r.stored, (int32) SLICE_BYTES));
	}
	else if (VARATT_IS_COMPRESSED(attr))
	{
		r.stored = VARSIZE(attr) - VARHDRSZ;
		r.rawsize = VARDATA_COMPRESSED_GET_EXTSIZE(attr);
		r.method = (int) VARDATA_COMPRESSED_GET_COMPRESS_METHOD(attr);
		if (r.method != TOAST_PGLZ_COMPRESSION_ID &&
			r.method != TOAST_LZ4_COMPRESSION_ID)
			return false;
		r.fetched = r.stored;
		r.in = (const uint8 *) VARDATA(attr);
		r.in_end = r.in + r.stored;
	}
	else
		return false;

	/* from here on an ERROR, a cancel included, says what was being read */
	errcb.callback = toast_read_context;
	errcb.arg = &r;
	errcb.previous = error_context_stack;
	error_context_stack = &errcb;

	r.src.size = r.rawsize;
	r.src.whole = PointerGetDatum(attr);
	if (r.method == -1)
		r.src.next = plain_next;
	else
	{
		/*
		 * The stored bytes start with the 4-byte header of the compressed
		 * value: its raw size (checked against the pointer's) and method.
		 */
		uint32		tcinfo;

		r.src.next = compressed_next;
		if (r.toastrel != NULL)
		{
			r.inbuf = palloc(PGLZ_GROUP_IN + Min(r.stored, (int32) SLICE_BYTES));
			r.in = r.in_end = (const uint8 *) r.inbuf;
		}
		if (!toast_input(&r, sizeof(tcinfo)))
			toast_corrupt(&r);
		memcpy(&tcinfo, r.in, sizeof(tcinfo));
		r.in += sizeof(tcinfo);
		if ((tcinfo & VARLENA_EXTSIZE_MASK) != r.rawsize)
			toast_corrupt(&r);
		r.history = r.method == TOAST_LZ4_COMPRESSION_ID ? LZ4_HISTORY : PGLZ_HISTORY;
		r.out = palloc(Min(r.history + PIECE_BYTES, r.rawsize));
		r.step = LZ4_TOKEN;
	}

	/*
	 * A value with arcs, for a buffer that strokes them, is read whole here
	 * first (so checked) and read again stroked from r.src.whole.
	 */
	(void) tdc_gser_append_source(buf, &r.src, fname);

	/* every stored byte must have been used, and no more */
	if (r.method != -1 &&
		(r.produced != r.rawsize || r.in != r.in_end || r.fetched != r.stored ||
		 (r.method == TOAST_LZ4_COMPRESSION_ID && r.step != LZ4_END)))
	{
		/* a lz4 block may end in an empty last sequence: decode it */
		if (r.method == TOAST_LZ4_COMPRESSION_ID && r.produced == r.rawsize &&
			r.step != LZ4_END)
			lz4_piece(&r, r.out_pos + 1);
		if (r.step != LZ4_END || r.in != r.in_end || r.fetched != r.stored)
			toast_corrupt(&r);
	}
	error_context_stack = errcb.previous;

	if (r.toastrel != NULL)
		table_close(r.toastrel, AccessShareLock);
	if (r.slice)
		pfree(r.slice);
	if (r.inbuf)
		pfree(r.inbuf);
	if (r.out)
		pfree(r.out);
	return true;
}

/* ----------------------------------------------------------------
 *		SQL entry points
 * ----------------------------------------------------------------
 */

PG_FUNCTION_INFO_V1(st_tdcdelaunaytriangles);

/*
 * ST_TDCDelaunayTriangles(geometry, tolerance float8, flags int4)
 *		drop-in for ST_DelaunayTriangles; STRICT like it.
 */
Datum
st_tdcdelaunaytriangles(PG_FUNCTION_ARGS)
{
	const char *fname = "ST_TDCDelaunayTriangles";
	struct varlena *arg = (struct varlena *) DatumGetPointer(PG_GETARG_DATUM(0));
	double		tolerance = PG_NARGS() > 1 ? PG_GETARG_FLOAT8(1) : 0.0;
	int32		flags = PG_NARGS() > 2 ? PG_GETARG_INT32(2) : 0;
	TdcPointBuf buf;

	instr_time	start;

	tdc_signal_guard();
	tdc_check_params(tolerance, flags, fname);
	if (tdc_guc_stats)
		INSTR_TIME_SET_CURRENT(start);
	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = TDC_CURVES_STROKE;
	if (!read_toasted_value(&buf, arg, fname))
		tdc_gser_append(&buf, PG_DETOAST_DATUM_PACKED(PointerGetDatum(arg)),
						fname);
	PG_RETURN_DATUM(triangulate_to_datum(&buf, tolerance, flags, fname,
										 tdc_guc_stats ? ms_since(start) : -1));
}

/*
 * The rows of a Dump function: one POLYGON per triangle of run's finished
 * job, numbered from 1, into the materialized result of rsinfo.
 */
void
tdc_dump_triangles(struct ReturnSetInfo *rsinfo, TdcRun *run, const TdcPointBuf *buf)
{
	struct varlena *tri = palloc(tdc_gser_triangle_size(buf->hasz));
	tdc_iter	it;
	uint32		v[3];
	int64		id = 0;
	Datum		values[2];
	bool		nulls[2] = {false, false};

	it.pos = 0;
	while (tdc_next_triangle(run->job, &it, v))
	{
		tdc_gser_write_triangle(tri, run->job, v, buf);
		values[0] = Int64GetDatum(++id);
		values[1] = PointerGetDatum(tri);
		tuplestore_putvalues(rsinfo->setResult, rsinfo->setDesc, values, nulls);
		if ((id & (DUMP_POLL_ROWS - 1)) == 0)
			CHECK_FOR_INTERRUPTS();
	}
	CHECK_FOR_INTERRUPTS();
	pfree(tri);
}

PG_FUNCTION_INFO_V1(st_tdcdelaunaydump);

/*
 * ST_TDCDelaunayDump(query text, tolerance float8)
 *		RETURNS TABLE(id bigint, geom geometry)
 */
Datum
st_tdcdelaunaydump(PG_FUNCTION_ARGS)
{
	const char *fname = "ST_TDCDelaunayDump";
	ReturnSetInfo *rsinfo = (ReturnSetInfo *) fcinfo->resultinfo;
	char	   *query;
	double		tolerance;
	Oid			geomoid;
	TdcPointBuf buf;
	TdcRun	   *run;

	tdc_signal_guard();
	/* STRICT: a NULL query or tolerance gives no rows, as in PostGIS */
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	tolerance = PG_GETARG_FLOAT8(1);
	tdc_check_params(tolerance, TDC_OUT_POLYGONS, fname);

#if PG_VERSION_NUM >= 150001
	InitMaterializedSRF(fcinfo, 0);
#else
	SetSingleFuncCall(fcinfo, 0);
#endif
	geomoid = TupleDescAttr(rsinfo->setDesc, 1)->atttypid;

	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = TDC_CURVES_STROKE;
	tdc_dump_collect(&buf, NULL, query, geomoid, fname, NULL, NULL);
	if (buf.n == 0)
		return (Datum) 0;

	run = tdc_run(&buf, tolerance, 0, fname);
	if (tdc_guc_stats)
	{
		RunStats	st;

		stats_take(run->job, &st);
		stats_report(&st, fname, "");
	}

	tdc_dump_triangles(rsinfo, run, &buf);
	tdc_run_free(run);
	return (Datum) 0;
}
