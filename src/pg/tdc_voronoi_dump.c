/*
 * tdc_voronoi_dump.c
 *		ST_TDCVoronoiDump(query, extend_to): the Voronoi cell of every vertex
 *		a query returns, keyed by the id of its row.
 *
 * The query returns (id bigint, geom geometry); it is run as the caller,
 * and must be a plain read-only SELECT, as for ST_TDCDelaunayDump.  Every
 * vertex of every row's geometry gives one output row (id, cell), in the
 * query's order: a vertex that duplicates another (or that a tolerance
 * merged, when there is one) gets that site's cell, so the cells can be
 * joined back to the rows that made them.  Rows with a NULL geometry are
 * skipped; a NULL id is an error.  The rows go through a tuplestore that
 * spills to disk past work_mem, so the result is not bound by 1 GB.  With
 * fewer than 2 distinct vertices there is no diagram (ST_VoronoiPolygons
 * gives an empty collection) and no row.
 */
#include "postgres.h"

#include "catalog/pg_type.h"
#include "executor/spi.h"
#include "funcapi.h"
#include "miscadmin.h"
#include "utils/builtins.h"
#include "utils/lsyscache.h"
#include "utils/memutils.h"
#include "utils/tuplestore.h"

#include "tdc_voronoi.h"

#define VDUMP_BATCH			10000

static void
vdump_error_context(void *arg)
{
	errcontext("query of ST_TDCVoronoiDump: %s", (const char *) arg);
}

typedef struct IdBuf
{
	int64	   *id;
	Size		n;
	Size		cap;
} IdBuf;

static void
idbuf_fill(IdBuf *ids, Size upto, int64 id, MemoryContext cxt)
{
	if (upto > ids->cap)
	{
		Size		cap = Max(upto, ids->cap * 2);

		cap = Max(cap, 1024);
		ids->id = ids->id == NULL ?
			MemoryContextAllocHuge(cxt, cap * sizeof(int64)) :
			repalloc_huge(ids->id, cap * sizeof(int64));
		ids->cap = cap;
	}
	while (ids->n < upto)
		ids->id[ids->n++] = id;
}

/* Run the query; the vertices into buf, each one's row id into ids. */
static void
vdump_collect(TdcPointBuf *buf, IdBuf *ids, const char *query, Oid geomoid,
			  const char *fname)
{
	ErrorContextCallback errcb;
	SPIPlanPtr	plan;
	Portal		portal;
	TupleDesc	desc;
	Oid			idtype;
	MemoryContext outer = CurrentMemoryContext;

	errcb.callback = vdump_error_context;
	errcb.arg = (void *) query;
	errcb.previous = error_context_stack;
	error_context_stack = &errcb;

	if (SPI_connect() != SPI_OK_CONNECT)
		elog(ERROR, "%s: SPI_connect failed", fname);
	plan = SPI_prepare(query, 0, NULL);
	if (plan == NULL)
		elog(ERROR, "%s: could not prepare the query: %s", fname,
			 SPI_result_code_string(SPI_result));
	if (!SPI_is_cursor_plan(plan))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the query must be a single SELECT returning (id bigint, geom geometry)",
						fname)));
	tdc_dump_check_read_only(plan, fname);
	portal = SPI_cursor_open(NULL, plan, NULL, NULL, true);
	desc = portal->tupDesc;
	if (desc == NULL || desc->natts != 2)
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the query must return two columns (id bigint, geom geometry), it returns %d",
						fname, desc ? desc->natts : 0)));
	idtype = getBaseType(TupleDescAttr(desc, 0)->atttypid);
	if (idtype != INT8OID && idtype != INT4OID && idtype != INT2OID)
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the query's first column must be an integer id, not %s",
						fname, format_type_be(TupleDescAttr(desc, 0)->atttypid))));
	if (getBaseType(TupleDescAttr(desc, 1)->atttypid) != geomoid)
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the query's second column must be of type geometry, not %s",
						fname, format_type_be(TupleDescAttr(desc, 1)->atttypid))));

	for (;;)
	{
		SPI_cursor_fetch(portal, true, VDUMP_BATCH);
		if (SPI_processed == 0)
			break;
		for (uint64 i = 0; i < SPI_processed; i++)
		{
			bool		gnull,
						inull;
			Datum		g = SPI_getbinval(SPI_tuptable->vals[i], SPI_tuptable->tupdesc, 2, &gnull);
			Datum		d = SPI_getbinval(SPI_tuptable->vals[i], SPI_tuptable->tupdesc, 1, &inull);
			struct varlena *gv;
			int64		id;

			if (gnull)
				continue;
			if (inull)
				ereport(ERROR,
						(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
						 errmsg("%s: the query returned a NULL id", fname)));
			id = idtype == INT8OID ? DatumGetInt64(d) :
				idtype == INT4OID ? (int64) DatumGetInt32(d) : (int64) DatumGetInt16(d);
			gv = PG_DETOAST_DATUM_PACKED(g);
			tdc_gser_append(buf, gv, fname);
			if ((Pointer) gv != DatumGetPointer(g))
				pfree(gv);
			idbuf_fill(ids, (Size) buf->n, id, outer);
		}
		SPI_freetuptable(SPI_tuptable);
		CHECK_FOR_INTERRUPTS();
	}
	SPI_cursor_close(portal);
	SPI_finish();
	error_context_stack = errcb.previous;
}

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
	IdBuf		ids = {NULL, 0, 0};
	TdcRun	   *run;
	VorRun	   *vrun;
	const tdc_voronoi *v;
	MemoryContext rowcxt;
	Datum		values[2];
	bool		nulls[2] = {false, false};

	tdc_signal_guard();
#if PG_VERSION_NUM >= 150001
	InitMaterializedSRF(fcinfo, 0);
#else
	SetSingleFuncCall(fcinfo, 0);
#endif
	/* a NULL query gives no rows, as ST_TDCDelaunayDump's */
	if (PG_ARGISNULL(0))
		return (Datum) 0;
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	if (PG_NARGS() > 1 && !PG_ARGISNULL(1))
	{
		tdc_voronoi_extend_to_box((struct varlena *) PG_DETOAST_DATUM(PG_GETARG_DATUM(1)),
								  ext, fname);
		have_ext = true;
	}
	geomoid = TupleDescAttr(rsinfo->setDesc, 1)->atttypid;

	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	vdump_collect(&buf, &ids, query, geomoid, fname);
	vrun = tdc_voronoi_run(&buf, 0.0, have_ext ? ext : NULL, &run, fname);
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
