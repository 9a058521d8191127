/*
 * tdc_constrained.c
 *		ST_TDCConstrainedDelaunayTriangles: the constrained Delaunay
 *		triangulation of a geometry's vertices, its linework as constraints.
 *
 * The vertices are read by the same reader as ST_TDCDelaunayTriangles
 * (gserialized.c: NaN and infinities rejected, Z kept, M dropped, SRID
 * carried), in the order they are stored.  The segments come from a second,
 * structural walk over the same value here: every linestring and every
 * polygon ring (triangles and the faces of TINs and polyhedral surfaces
 * included) contributes the segments between its consecutive vertices, as
 * indices into that vertex order; points contribute none.  The reader has
 * already checked the value, so this walk only has to count the same way,
 * and still checks every count against the bytes left.
 *
 * The triangulation runs as usual (tdc_run), then the segments are inserted
 * by the core (cdt.c) on a thread of its own, while this backend waits in
 * 10 ms slices and watches for interrupts.  A proper crossing is an ERROR
 * that names both segments by their end points: an exact triangulation
 * cannot invent the crossing point, so the lines must be noded first.
 */
#include "postgres.h"

#include <math.h>

#include "miscadmin.h"
#include "utils/memutils.h"

#include "gser_format.h"
#include "tdc_pg.h"

typedef struct SegWalk
{
	const char *p;
	const char *end;
	Size		vsize;			/* bytes per vertex */
	uint64		nvert;			/* vertices counted so far */
	uint32	   *seg;			/* pairs of vertex indices */
	uint64		nseg;
	uint64		cap;
	const char *fname;
} SegWalk;

static void
seg_corrupt(const SegWalk *w)
{
	ereport(ERROR,
			(errcode(ERRCODE_DATA_CORRUPTED),
			 errmsg("%s: corrupt geometry value", w->fname)));
}

static uint32
seg_u32(SegWalk *w)
{
	uint32		v;

	if (w->end - w->p < 4)
		seg_corrupt(w);
	memcpy(&v, w->p, 4);
	w->p += 4;
	return v;
}

/* A chain of k vertices: its k - 1 segments, then skip the vertices. */
static void
seg_chain(SegWalk *w, uint32 k, bool segments)
{
	if ((uint64) k * w->vsize > (uint64) (w->end - w->p))
		seg_corrupt(w);
	if (segments && k > 1)
	{
		if (w->nseg + k - 1 > w->cap)
		{
			uint64		cap = Max(w->cap * 2, w->nseg + k - 1);

			w->seg = w->seg ? repalloc_huge(w->seg, cap * 2 * sizeof(uint32))
				: MemoryContextAllocHuge(CurrentMemoryContext, cap * 2 * sizeof(uint32));
			w->cap = cap;
		}
		for (uint32 i = 0; i + 1 < k; i++)
		{
			w->seg[2 * w->nseg] = (uint32) (w->nvert + i);
			w->seg[2 * w->nseg + 1] = (uint32) (w->nvert + i + 1);
			w->nseg++;
		}
	}
	w->nvert += k;
	w->p += (Size) k * w->vsize;
}

static void
seg_geom(SegWalk *w)
{
	uint32		type,
				count;

	check_stack_depth();
	CHECK_FOR_INTERRUPTS();
	type = seg_u32(w);
	count = seg_u32(w);
	switch (type)
	{
		case G_POINT:
			seg_chain(w, count, false);
			return;
		case G_LINE:
		case G_TRIANGLE:
			seg_chain(w, count, true);
			return;
		case G_POLYGON:
			{
				const char *sizes = w->p;

				if ((uint64) count * 4 + (count % 2) * 4 > (uint64) (w->end - w->p))
					seg_corrupt(w);
				w->p += (Size) count * 4 + (count % 2) * 4;
				for (uint32 i = 0; i < count; i++)
				{
					uint32		k;

					memcpy(&k, sizes + 4 * (Size) i, 4);
					seg_chain(w, k, true);
				}
				return;
			}
		case G_MULTIPOINT:
		case G_MULTILINE:
		case G_MULTIPOLYGON:
		case G_COLLECTION:
		case G_POLYHEDRAL:
		case G_TIN:
			for (uint32 i = 0; i < count; i++)
				seg_geom(w);
			return;
	}
	/* the vertex reader rejected curves and unknown types already */
	seg_corrupt(w);
}

/* The segments of a detoasted value whose vertices buf already holds. */
static void
collect_segments(const struct varlena *geom, SegWalk *w, const char *fname)
{
	const unsigned char *h = (const unsigned char *) VARDATA_ANY(geom);
	uint8		gflags;
	int			ndims;

	memset(w, 0, sizeof(*w));
	w->fname = fname;
	w->p = (const char *) h;
	w->end = (const char *) geom + VARSIZE_ANY(geom);
	if (w->end - w->p < 8)
		seg_corrupt(w);
	gflags = h[3];
	ndims = 2 + ((gflags & GF_Z) ? 1 : 0) + ((gflags & GF_M) ? 1 : 0);
	w->vsize = ndims * sizeof(double);
	w->p += 4;
	if ((gflags & GF_VERSION) && (gflags & GF_EXTENDED))
		w->p += 8;
	if (gflags & GF_BBOX)
		w->p += sizeof(float) * ((gflags & GF_GEODETIC) ? 6 : 2 * ndims);
	if (w->p > w->end)
		seg_corrupt(w);
	seg_geom(w);
}

/* ----------------------------------------------------------------
 *		running the insertion
 * ----------------------------------------------------------------
 */

typedef struct CdtHold
{
	tdc_cdt    *cdt;
} CdtHold;

/* On error or cancel: stop and free the insertion before the job goes. */
static void
cdt_reset_callback(void *arg)
{
	CdtHold    *hold = (CdtHold *) arg;

	if (hold->cdt != NULL)
	{
		tdc_cdt_free(hold->cdt);
		hold->cdt = NULL;
	}
}

static void
report_crossing(const CdtHold *hold, const TdcPointBuf *buf, const SegWalk *w,
				const char *fname)
{
	size_t		s1,
				s2;

	if (tdc_cdt_crossing(hold->cdt, &s1, &s2))
	{
		const double *a = buf->xy + 2 * (size_t) w->seg[2 * s1],
				   *b = buf->xy + 2 * (size_t) w->seg[2 * s1 + 1],
				   *c = buf->xy + 2 * (size_t) w->seg[2 * s2],
				   *d = buf->xy + 2 * (size_t) w->seg[2 * s2 + 1];

		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: segments LINESTRING(%.17g %.17g,%.17g %.17g) and LINESTRING(%.17g %.17g,%.17g %.17g) cross",
						fname, a[0], a[1], b[0], b[1], c[0], c[1], d[0], d[1]),
				 errdetail("An exact constrained triangulation cannot create their crossing point."),
				 errhint("Node the lines first, with ST_Node or ST_UnaryUnion.")));
	}
}

/*
 * Insert the segments into the finished job of run, waiting interruptibly.
 * Any failure is an ERROR; the insertion is freed with buf's context.
 */
static void
constrain(TdcRun *run, const TdcPointBuf *buf, const SegWalk *w,
		  const char *fname)
{
	CdtHold    *hold;
	MemoryContextCallback *cb;
	char		err[512];
	int			rc;

	hold = MemoryContextAllocZero(buf->cxt, sizeof(CdtHold));
	cb = MemoryContextAllocZero(buf->cxt, sizeof(MemoryContextCallback));
	cb->func = cdt_reset_callback;
	cb->arg = hold;
	/* registered after the job's: runs before it, so the job outlives it */
	MemoryContextRegisterResetCallback(buf->cxt, cb);

	err[0] = '\0';
	rc = tdc_cdt_start(run->job, w->seg, (size_t) w->nseg, &hold->cdt, err,
					   sizeof(err));
	if (rc != TDC_OK)
		ereport(ERROR,
				(errcode(rc == TDC_EMEMLIMIT ? ERRCODE_PROGRAM_LIMIT_EXCEEDED :
						 rc == TDC_ENOMEM ? ERRCODE_OUT_OF_MEMORY :
						 ERRCODE_INTERNAL_ERROR),
				 errmsg("%s: %s", fname, err)));
	while ((rc = tdc_cdt_wait(hold->cdt, 10)) == TDC_RUNNING)
	{
		if (!InterruptPending)
			continue;
		if (QueryCancelPending || ProcDiePending)
		{
			tdc_cdt_cancel(hold->cdt);
			(void) tdc_cdt_wait(hold->cdt, -1);
			CHECK_FOR_INTERRUPTS();
			ereport(ERROR,
					(errcode(ERRCODE_QUERY_CANCELED),
					 errmsg("%s: triangulation canceled", fname)));
		}
		CHECK_FOR_INTERRUPTS();
	}
	if (rc == TDC_ECROSS)
		report_crossing(hold, buf, w, fname);
	if (rc != TDC_OK)
		ereport(ERROR,
				(errcode(rc == TDC_ECANCELED ? ERRCODE_QUERY_CANCELED :
						 rc == TDC_ENOMEM ? ERRCODE_OUT_OF_MEMORY :
						 ERRCODE_INTERNAL_ERROR),
				 errmsg("%s: %s", fname, tdc_cdt_error(hold->cdt))));
	/* the mesh is final; the constraint numbers are not needed for output */
	tdc_cdt_free(hold->cdt);
	hold->cdt = NULL;
}

PG_FUNCTION_INFO_V1(st_tdcconstraineddelaunaytriangles);

/*
 * ST_TDCConstrainedDelaunayTriangles(geometry, flags int4)
 *		comparable to SFCGAL's ST_ConstrainedDelaunayTriangles; STRICT.
 */
Datum
st_tdcconstraineddelaunaytriangles(PG_FUNCTION_ARGS)
{
	const char *fname = "ST_TDCConstrainedDelaunayTriangles";
	struct varlena *geom = PG_DETOAST_DATUM(PG_GETARG_DATUM(0));
	int32		flags = PG_NARGS() > 1 ? PG_GETARG_INT32(1) : 0;
	TdcPointBuf buf;
	SegWalk		w;
	TdcRun	   *run;
	TdcGserWriter wr;
	struct varlena *result;
	uint64		extra;

	tdc_check_params(0.0, flags, fname);
	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	tdc_gser_append(&buf, geom, fname);
	if (buf.n == 0)
		PG_RETURN_POINTER(tdc_gser_empty(flags, buf.srid));
	if (buf.n > TDC_MAX_POINTS)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: %llu vertices exceed the limit of %zu", fname,
						(unsigned long long) buf.n, TDC_MAX_POINTS)));
	collect_segments(geom, &w, fname);
	if (w.nvert != buf.n)
		seg_corrupt(&w);

	/*
	 * The result and the segments, for max_memory; tdc_cdt_start adds the
	 * insertion's own arrays (tdc_cdt_memory) to the engine's estimate.
	 */
	extra = tdc_gser_result_bound(buf.n, flags, buf.hasz) +
		w.nseg * 2 * sizeof(uint32);
	run = tdc_run(&buf, 0.0, extra, fname);
	constrain(run, &buf, &w, fname);

	result = tdc_gser_result_alloc(run->job, flags, &buf, fname, &wr);
	if (flags == TDC_OUT_EDGES || wr.count == 0 ||
		!tdc_run_emit(run, tdc_gser_emit, &wr, fname))
		tdc_gser_fill(&wr);
	CHECK_FOR_INTERRUPTS();
	tdc_run_free(run);
	PG_RETURN_POINTER(result);
}
