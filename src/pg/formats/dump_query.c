/*
 * dump_query.c
 *		The query of a Dump function (ST_TDCDelaunayDump, ST_TDCVoronoiDump):
 *		refuse it unless it only reads, run it, and collect the vertices of
 *		its geometry column, with the id of each vertex's row when asked,
 *		or each row's tag (tdc_delaunay_tiled's tile column), when the query
 *		has one, for a callback; or, for the tiled procedures over a pcpatch
 *		column, the X, Y, Z of its patches (tdc_dump_collect_pc).
 *
 * The query runs through SPI as the calling user (the Dump functions are
 * not SECURITY DEFINER), read-only, behind a cursor fetched in batches of
 * DUMP_BATCH rows with an interrupt check after each, so its result never
 * has to fit in memory as rows: only the vertices (and ids) are kept.  An
 * ERROR raised while the query runs carries a CONTEXT line naming the
 * function and the query, and one that says a name was not found carries a
 * HINT to schema-qualify the names (see tdc_dump_collect).
 */
#include "postgres.h"

#include "catalog/pg_type.h"
#include "executor/spi.h"
#include "miscadmin.h"
#include "utils/builtins.h"
#include "utils/lsyscache.h"
#include "utils/memutils.h"
#include "utils/plancache.h"

#include "tdc_pg.h"

/* Rows fetched from the query at a time. */
#define DUMP_BATCH			10000

typedef struct DumpContext
{
	const char *fname;
	const char *query;
} DumpContext;

static void
dump_error_context(void *arg)
{
	const DumpContext *c = (const DumpContext *) arg;

	errcontext("query of %s: %s", c->fname, c->query);
}

/*
 * The query is documented as a SELECT that reads: refuse, before it runs,
 * every statement that would write (INSERT, UPDATE, DELETE or MERGE with
 * RETURNING, a data-modifying WITH, SELECT ... FOR UPDATE/SHARE), so that
 * a function meant to triangulate never changes data.  Functions the query
 * calls run as they would anywhere else.
 */
static void
dump_check_read_only(SPIPlanPtr plan, const char *fname)
{
	ListCell   *ls;

	foreach(ls, SPI_plan_get_plan_sources(plan))
	{
		CachedPlanSource *ps = (CachedPlanSource *) lfirst(ls);
		ListCell   *lq;

		foreach(lq, ps->query_list)
		{
			Query	   *q = lfirst_node(Query, lq);
			const char *what = NULL;

			if (q->commandType != CMD_SELECT)
				what = "it is not a SELECT";
			else if (q->hasModifyingCTE)
				what = "it has a data-modifying WITH";
			else if (q->rowMarks != NIL)
				what = "it locks rows (FOR UPDATE or FOR SHARE)";
			if (what)
				ereport(ERROR,
						(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
						 errmsg("%s: the query must be a plain SELECT that only reads: %s",
								fname, what)));
		}
	}
}

/*
 * Give ids[n .. upto-1] the id "id", growing the array in "cxt"; it counts
 * with buf's vertices against tdc_delaunay.max_memory.
 */
static void
idbuf_fill(TdcIdBuf *ids, Size upto, int64 id, MemoryContext cxt,
		   TdcPointBuf *buf, const char *fname)
{
	if (upto > ids->cap)
	{
		Size		cap = Max(upto, ids->cap * 2);

		cap = Max(cap, 1024);
		tdc_pointbuf_side_grow(buf, (uint64) ids->cap * sizeof(int64),
							   (uint64) cap * sizeof(int64), "their row ids", fname);
		ids->id = ids->id == NULL ?
			MemoryContextAllocHuge(cxt, cap * sizeof(int64)) :
			repalloc_huge(ids->id, cap * sizeof(int64));
		ids->cap = cap;
	}
	while (ids->n < upto)
		ids->id[ids->n++] = id;
}

/*
 * Check the query's columns: (geometry) without ids, (integer id, geometry)
 * with them; with tags (geometry) or (geometry, tag of any type).  Returns
 * the id column's base type (InvalidOid without ids).
 */
static Oid
dump_check_columns(TupleDesc desc, bool with_ids, bool with_tags, Oid geomoid,
				   const char *fname)
{
	Oid			idtype = InvalidOid;
	int			gcol = with_ids ? 1 : 0;

	if (with_tags && (desc == NULL || desc->natts < 1 || desc->natts > 2))
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the query must return (geom geometry) or (geom geometry, tile), it returns %d columns",
						fname, desc ? desc->natts : 0)));
	if (desc == NULL || (!with_tags && desc->natts != (with_ids ? 2 : 1)))
	{
		if (with_ids)
			ereport(ERROR,
					(errcode(ERRCODE_DATATYPE_MISMATCH),
					 errmsg("%s: the query must return two columns (id bigint, geom geometry), it returns %d",
							fname, desc ? desc->natts : 0)));
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the query must return exactly one column of type geometry, it returns %d columns",
						fname, desc ? desc->natts : 0)));
	}
	if (with_ids)
	{
		idtype = getBaseType(TupleDescAttr(desc, 0)->atttypid);
		if (idtype != INT8OID && idtype != INT4OID && idtype != INT2OID)
			ereport(ERROR,
					(errcode(ERRCODE_DATATYPE_MISMATCH),
					 errmsg("%s: the query's first column must be an integer id, not %s",
							fname, format_type_be(TupleDescAttr(desc, 0)->atttypid))));
	}
	if (getBaseType(TupleDescAttr(desc, gcol)->atttypid) != geomoid)
		ereport(ERROR,
				(errcode(ERRCODE_DATATYPE_MISMATCH),
				 errmsg("%s: the query's %scolumn must be of type geometry, not %s",
						fname, with_ids ? "second " : "",
						format_type_be(TupleDescAttr(desc, gcol)->atttypid))));
	return idtype;
}

/*
 * Run "query" and append the vertices of its geometry column (of type
 * geomoid) to buf, skipping rows whose geometry is NULL.  With ids NULL the
 * query returns that one column; otherwise it returns (id, geometry) with an
 * integer id that must not be NULL, and ids->id[k] becomes the id of the
 * row vertex k came from (ids grows in the caller's memory context, so
 * ids->n == buf->n afterwards when both started empty).  SPI is connected
 * and finished here; buf's context is the caller's, so the vertices
 * outlive SPI_finish.  row_fn, when not NULL, sees each geometry read
 * (see TdcDumpRowFn); it allocates in its own context, not SPI's.
 */
static void
dump_collect(TdcPointBuf *buf, TdcIdBuf *ids, const char *query,
			 Oid geomoid, TdcPcColumn *pc, const char *fname, TdcDumpRowFn row_fn,
			 void *row_arg, const TdcDumpTagOps *tag_ops)
{
	ErrorContextCallback errcb;
	DumpContext dc;
	SPIPlanPtr	plan;
	Portal		portal;
	Oid			idtype;
	int			gcol = ids ? 2 : 1;
	MemoryContext outer = CurrentMemoryContext;
	TdcDumpTag	tag = {0};
	TdcDumpTag *tagp = NULL;

	dc.fname = fname;
	dc.query = query;
	errcb.callback = dump_error_context;
	errcb.arg = (void *) &dc;
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
				 errmsg("%s: the query must be a single SELECT returning %s",
						fname, ids ? "(id bigint, geom geometry)" : "one geometry column")));
	dump_check_read_only(plan, fname);
	/* read-only: SPI refuses anything that would write, as a second guard */
	portal = SPI_cursor_open(NULL, plan, NULL, NULL, true);
	idtype = dump_check_columns(portal->tupDesc, ids != NULL, tag_ops != NULL, geomoid, fname);
	if (tag_ops && portal->tupDesc->natts == 2)
	{
		Form_pg_attribute att = TupleDescAttr(portal->tupDesc, 1);

		tagp = &tag;
		tag.typid = att->atttypid;
		tag.typmod = att->atttypmod;
		tag.name = pstrdup(NameStr(att->attname));
	}
	if (tag_ops)
		tag_ops->columns(row_arg, tagp);

	for (;;)
	{
		SPI_cursor_fetch(portal, true, DUMP_BATCH);
		if (SPI_processed == 0)
			break;
		for (uint64 i = 0; i < SPI_processed; i++)
		{
			bool		gnull,
						inull;
			Datum		g = SPI_getbinval(SPI_tuptable->vals[i],
										  SPI_tuptable->tupdesc, gcol, &gnull);
			Datum		d;
			int64		id = 0;
			uint64		first;

			if (gnull)
				continue;
			if (ids)
			{
				d = SPI_getbinval(SPI_tuptable->vals[i],
								  SPI_tuptable->tupdesc, 1, &inull);
				if (inull)
					ereport(ERROR,
							(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
							 errmsg("%s: the query returned a NULL id", fname)));
				id = idtype == INT8OID ? DatumGetInt64(d) :
					idtype == INT4OID ? (int64) DatumGetInt32(d) :
					(int64) DatumGetInt16(d);
			}
			first = buf->n;
			if (pc)
				tdc_pc_append_patch(buf, &pc->src, pc->cxt, NULL, g, pc->filter, "column", fname);
			else
				(void) tdc_read_geometry(buf, g, fname);
			if (tagp)
				tag.value = SPI_getbinval(SPI_tuptable->vals[i], SPI_tuptable->tupdesc, 2,
										  &tag.isnull);
			if (tag_ops)
				tag_ops->row(row_arg, first, tagp);
			if (row_fn)
				row_fn(row_arg, first);
			if (ids)
				idbuf_fill(ids, (Size) buf->n, id, outer, buf, fname);
		}
		SPI_freetuptable(SPI_tuptable);
		CHECK_FOR_INTERRUPTS();
	}
	SPI_cursor_close(portal);
	SPI_finish();
	error_context_stack = errcb.previous;
}

/*
 * The query is text, so its names are looked up when it runs, in the
 * search_path of the moment.  pg_restore empties it, and PostgreSQL 17+
 * sets it to pg_catalog, pg_temp while it creates or refreshes a
 * materialized view: a materialized view over a Dump function whose query
 * names "pts" rather than "public.pts" then fails to refresh.  An error that says a table,
 * function, operator or type was not found gets a HINT that says so (after
 * the hint it had, if any); it keeps its code, message and CONTEXT.
 */
static void
dump_collect_hinted(TdcPointBuf *buf, TdcIdBuf *ids, const char *query,
					Oid geomoid, TdcPcColumn *pc, const char *fname, TdcDumpRowFn row_fn,
					void *row_arg, const TdcDumpTagOps *tag_ops)
{
	MemoryContext outer = CurrentMemoryContext;

	PG_TRY();
	{
		dump_collect(buf, ids, query, geomoid, pc, fname, row_fn, row_arg, tag_ops);
	}
	PG_CATCH();
	{
		ErrorData  *edata;
		const char *hint = "Schema-qualify every table, function and type in the query (public.pts, not pts): "
			"its names are looked up in the search_path it runs in, which pg_restore empties, "
			"and which is pg_catalog, pg_temp in a materialized view from PostgreSQL 17 on.";

		MemoryContextSwitchTo(outer);
		edata = CopyErrorData();
		if (edata->sqlerrcode != ERRCODE_UNDEFINED_TABLE &&
			edata->sqlerrcode != ERRCODE_UNDEFINED_FUNCTION &&
			edata->sqlerrcode != ERRCODE_UNDEFINED_OBJECT)
		{
			FreeErrorData(edata);
			PG_RE_THROW();
		}
		FlushErrorState();
		edata->hint = edata->hint ? psprintf("%s\n%s", edata->hint, hint) : pstrdup(hint);
		ReThrowError(edata);
	}
	PG_END_TRY();
}

void
tdc_dump_collect(TdcPointBuf *buf, TdcIdBuf *ids, const char *query,
				 Oid geomoid, const char *fname, TdcDumpRowFn row_fn,
				 void *row_arg)
{
	dump_collect_hinted(buf, ids, query, geomoid, NULL, fname, row_fn, row_arg, NULL);
}

/*
 * The same for a query of (geometry) or (geometry, tag of any type): once
 * the query runs, ops->columns learns which (the tag column, or NULL), and
 * ops->row sees each row after its vertices were appended, the first at
 * index "first", with its tag (NULL without a tag column; NULL geometries
 * are skipped, NULL tags are not).
 */
void
tdc_dump_collect_tagged(TdcPointBuf *buf, const char *query, Oid geomoid,
						const char *fname, const TdcDumpTagOps *ops, void *arg)
{
	dump_collect_hinted(buf, NULL, query, geomoid, NULL, fname, NULL, arg, ops);
}

/*
 * The same two for a query whose column (of type coltype) holds
 * pgpointcloud patches: each patch's X, Y, Z (those the filter keeps) are
 * appended as a geometry's vertices would be (pcpatch_source.c).  Only the
 * tiled procedures' internal functions of tdc_delaunay_pointcloud come
 * here, so tdc_delaunay alone never reads a patch.
 */
void
tdc_dump_collect_pc(TdcPointBuf *buf, const char *query, Oid coltype, TdcPcColumn *pc,
					const char *fname, TdcDumpRowFn row_fn, void *row_arg)
{
	dump_collect_hinted(buf, NULL, query, coltype, pc, fname, row_fn, row_arg, NULL);
}

void
tdc_dump_collect_tagged_pc(TdcPointBuf *buf, const char *query, Oid coltype, TdcPcColumn *pc,
						   const char *fname, const TdcDumpTagOps *ops, void *arg)
{
	dump_collect_hinted(buf, NULL, query, coltype, pc, fname, NULL, arg, ops);
}
