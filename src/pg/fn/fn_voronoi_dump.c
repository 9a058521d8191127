/*
 * fn_voronoi_dump.c
 *		ST_TDCVoronoiDump(query, extend_to): the Voronoi cell of every vertex
 *		a query returns, keyed by the id of its row.
 *
 * The query returns (id bigint, geom geometry); it is run as the caller,
 * and must be a plain read-only SELECT, as for ST_TDCDelaunayDump (both
 * collect their query's vertices in dump_query.c).  Every vertex of
 * every row's geometry gives one output row (id, cell), in the query's
 * order: a vertex that duplicates another (or that a tolerance
 * merged, when there is one) gets that site's cell, so the cells can be
 * joined back to the rows that made them.  Rows with a NULL geometry are
 * skipped; a NULL id is an error.  The rows go through a tuplestore that
 * spills to disk past work_mem, so the result is not bound by 1 GB.  With
 * fewer than 2 distinct vertices there is no diagram (ST_VoronoiPolygons
 * gives an empty collection) and no row.
 */
#include "postgres.h"

#include "funcapi.h"
#include "miscadmin.h"
#include "utils/builtins.h"
#include "utils/memutils.h"
#include "utils/tuplestore.h"

#include "fn_voronoi.h"

PG_FUNCTION_INFO_V1(st_tdcvoronoidump);

Datum
st_tdcvoronoidump(PG_FUNCTION_ARGS)
{
	const char *fname = "ST_TDCVoronoiDump";
	ReturnSetInfo *rsinfo = (ReturnSetInfo *) fcinfo->resultinfo;
	char	   *query;
	double		ext[4];
	bool		have_ext = false;
	Oid			geomoid;
	TdcPointBuf buf;
	TdcIdBuf	ids = {NULL, 0, 0};
	TdcRun	   *run;
	VorRun	   *vrun;
	const tdc_voronoi *v;
	MemoryContext rowcxt;
	Datum		values[2];
	bool		nulls[2] = {false, false};

	tdc_signal_guard();
	InitMaterializedSRF(fcinfo, 0);
	/* a NULL query gives no rows, as ST_TDCDelaunayDump's */
	if (PG_ARGISNULL(0))
		return (Datum) 0;
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	if (PG_NARGS() > 1 && !PG_ARGISNULL(1))
	{
		tdc_voronoi_extend_to_box(PG_GETARG_DATUM(1),
								  ext, fname);
		have_ext = true;
	}
	geomoid = TupleDescAttr(rsinfo->setDesc, 1)->atttypid;

	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = TDC_CURVES_VERTICES;
	tdc_dump_collect(&buf, &ids, query, geomoid, fname, NULL, NULL);
	vrun = tdc_voronoi_run(&buf, 0.0, have_ext ? ext : NULL, NULL, &run, fname);
	if (vrun == NULL)
	{
		if (run)
			tdc_run_free(run);
		return (Datum) 0;
	}
	v = tdc_voronoi_of(vrun);

	/*
	 * Each row's POLYGON is made in a context reset per row: the tuplestore
	 * keeps its own copy, so only one value lives here at a time.
	 */
	rowcxt = AllocSetContextCreate(CurrentMemoryContext, "tdc voronoi dump row",
								   ALLOCSET_DEFAULT_SIZES);
	for (Size i = 0; i < ids.n; i++)
	{
		uint32		s = tdc_input_site(run->job, i);
		MemoryContext old;
		struct varlena *cell;

		if (s == UINT32_MAX)
			ereport(ERROR, (errcode(ERRCODE_OUT_OF_MEMORY),
							errmsg("out of memory mapping the input to its sites")));
		old = MemoryContextSwitchTo(rowcxt);
		cell = tdc_voronoi_cell_value(v, s, buf.srid);
		MemoryContextSwitchTo(old);
		values[0] = Int64GetDatum(ids.id[i]);
		values[1] = PointerGetDatum(cell);
		nulls[1] = cell == NULL;
		tuplestore_putvalues(rsinfo->setResult, rsinfo->setDesc, values, nulls);
		MemoryContextReset(rowcxt);
		if ((i & 0xffff) == 0)
			CHECK_FOR_INTERRUPTS();
	}
	MemoryContextDelete(rowcxt);
	CHECK_FOR_INTERRUPTS();
	tdc_voronoi_result_free(vrun, run);
	return (Datum) 0;
}
