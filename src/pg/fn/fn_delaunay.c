/*
 * fn_delaunay.c
 *		ST_TDCDelaunayTriangles and ST_TDCDelaunayDump: thin adapters over
 *		the runtime (read the argument, run, write the value or the rows).
 *
 * ST_TDCDelaunayTriangles reads its one value with tdc_read_geometry (a big
 * TOASTed value a slice at a time, toast_stream.c), triangulates it with
 * tdc_run (run.c) and writes one geometry value (gser_write.c), on the
 * core's threads when there are many triangles.
 *
 * ST_TDCDelaunayDump collects the vertices of its query's single geometry
 * column (dump_query.c), triangulates, and returns one POLYGON row per
 * triangle through a tuplestore, which spills to disk past work_mem.  So it
 * is not bound by the 1 GB limit of a single value.  tdc_dump_triangles,
 * which writes those rows, serves the constrained Dump too.
 */
#include "postgres.h"

#include "funcapi.h"
#include "miscadmin.h"
#include "portability/instr_time.h"
#include "utils/builtins.h"
#include "utils/tuplestore.h"

#include "tdc_pg.h"

/*
 * Dump rows put into the tuplestore between two interrupt checks: a row is
 * a small POLYGON value, and once the tuplestore spills to disk each costs
 * a write, so 65536 rows are some ms of work.  A power of two.
 */
#define DUMP_POLL_ROWS		65536

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
	TdcRunStats st;
	instr_time	start;
	double		write_ms = 0;

	if (buf->n == 0)
		return PointerGetDatum(tdc_gser_empty(flags, buf->srid));

	run = tdc_run(buf, tolerance,
				  tdc_gser_result_bound(buf->n, flags, buf->hasz), fname);
	if (tdc_guc_stats)
	{
		tdc_stats_take(run->job, &st);
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
		write_ms = tdc_ms_since(start);
		INSTR_TIME_SET_CURRENT(start);
	}
	tdc_run_free(run);
	if (tdc_guc_stats)
	{
		char		phases[160];
		char		read[40] = "";
		double		free_ms = tdc_ms_since(start);

		if (read_ms >= 0)
			snprintf(read, sizeof(read), "read %.3f ms, ", read_ms);
		/* kept: what the next run may take back (mem_cache.c) */
		snprintf(phases, sizeof(phases), "; %swrite %.3f ms, free %.3f ms, kept %llu kB",
				 read, write_ms, free_ms, tdc_backend_cache_kept_kb());
		tdc_stats_report(&st, fname, phases);
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
	(void) tdc_read_geometry(&buf, PG_GETARG_DATUM(0), fname);
	PG_RETURN_DATUM(triangulate_to_datum(&buf, tolerance, flags, fname,
										 tdc_guc_stats ? tdc_ms_since(start) : -1));
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

	InitMaterializedSRF(fcinfo, 0);
	geomoid = TupleDescAttr(rsinfo->setDesc, 1)->atttypid;

	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = TDC_CURVES_STROKE;
	tdc_dump_collect(&buf, NULL, query, geomoid, fname, NULL, NULL);
	if (buf.n == 0)
		return (Datum) 0;

	run = tdc_run(&buf, tolerance, 0, fname);
	if (tdc_guc_stats)
	{
		TdcRunStats st;

		tdc_stats_take(run->job, &st);
		tdc_stats_report(&st, fname, "");
	}

	tdc_dump_triangles(rsinfo, run, &buf);
	tdc_run_free(run);
	return (Datum) 0;
}
