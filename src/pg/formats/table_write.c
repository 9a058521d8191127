/*
 * table_write.c
 *		Rows of triangles written straight into a table the caller's
 *		transaction just created: (id bigint, tile, geom geometry), the
 *		tile of the caller's type (bigint, or a tile column's).
 *
 * tdc_delaunay_tiled writes millions of rows into its new target.  Through
 * SQL that cost twice: CREATE TABLE AS of a set-returning function first
 * stores the rows in a tuplestore (spilled to disk past work_mem) and then
 * inserts them, and the target's typmod, geometry(Polygon, srid), adds a
 * cast per row that PostGIS checks by reading the value: on 20 million
 * triangles the cast alone took 11 s of a 41 s statement.  Here each row is
 * formed once and inserted in batches with the table AM's bulk insert (a
 * BulkInsertState, no free space map, table_multi_insert as COPY uses it);
 * the values are ours, of the column's type and SRID by construction, so no
 * cast is needed.
 *
 * Because this bypasses what INSERT would do (privileges, triggers, row
 * security, constraints, typmods), it takes only a table that could not
 * have any: a plain table created in this transaction, owned by the
 * current user, with exactly those three columns, no index, no trigger,
 * no row security, no constraint.  The procedure creates it one statement
 * before; anything else is refused.
 */
#include "postgres.h"

#include "access/heapam.h"
#include "access/table.h"
#include "access/tableam.h"
#include "access/xact.h"
#include "catalog/pg_type.h"
#include "access/htup_details.h"
#include "executor/tuptable.h"
#include "miscadmin.h"
#include "utils/lsyscache.h"
#include "utils/memutils.h"
#include "utils/rel.h"
#include "utils/syscache.h"

#include "tdc_pg.h"

/*
 * Rows inserted at a time (table_multi_insert, as COPY inserts: the heap
 * logs a page's rows as one WAL record, where one row at a time logs a
 * record each), with an interrupt check after each batch.
 */
#define TW_BATCH			1000

/* Whether typid is a type named geometry (PostGIS's, in whatever schema). */
static bool
is_geometry(Oid typid)
{
	HeapTuple	tp = SearchSysCache1(TYPEOID, ObjectIdGetDatum(typid));
	bool		yes;

	if (!HeapTupleIsValid(tp))
		return false;
	yes = strcmp(NameStr(((Form_pg_type) GETSTRUCT(tp))->typname), "geometry") == 0;
	ReleaseSysCache(tp);
	return yes;
}

/* ERROR unless rel is a table of the shape and history described above. */
static void
check_target(Relation rel, const char *fname)
{
	TupleDesc	desc = RelationGetDescr(rel);
	const char *why = NULL;

	if (rel->rd_rel->relkind != RELKIND_RELATION)
		why = "it is not a plain table";
	else if (rel->rd_createSubid == InvalidSubTransactionId)
		why = "it was not created in this transaction";
	else if (rel->rd_rel->relowner != GetUserId())
		why = "it is not owned by the current user";
	else if (desc->natts != 3 ||
			 TupleDescAttr(desc, 0)->atttypid != INT8OID ||
			 !is_geometry(TupleDescAttr(desc, 2)->atttypid))
		why = "its columns are not (id bigint, tile, geom geometry)";
	else if (rel->rd_rel->relhasindex || rel->rd_rel->relhastriggers || rel->rd_rel->relrowsecurity ||
			 rel->rd_rel->relhasrules || (desc->constr != NULL && (desc->constr->num_check > 0 ||
																 desc->constr->has_not_null ||
																 desc->constr->num_defval > 0)))
		why = "it has an index, a trigger, a rule, row security or a constraint";
	if (why)
		ereport(ERROR,
				(errcode(ERRCODE_WRONG_OBJECT_TYPE),
				 errmsg("%s: cannot write into \"%s\": %s", fname, RelationGetRelationName(rel), why)));
}

/*
 * Open the target (RowExclusiveLock, kept to the end of the transaction),
 * checked; tw->geomoid is its geometry type, tw->tiletype and tiletypmod
 * its tile column's, which the caller checks against its tiles' before the
 * first row.  Rows come after tdc_table_writer_shape.
 */
void
tdc_table_writer_open(TdcTableWriter *tw, Oid relid, const char *fname)
{
	TupleDesc	desc;

	memset(tw, 0, sizeof(*tw));
	tw->rel = table_open(relid, RowExclusiveLock);
	check_target(tw->rel, fname);
	desc = RelationGetDescr(tw->rel);
	tw->geomoid = TupleDescAttr(desc, 2)->atttypid;
	tw->tiletype = TupleDescAttr(desc, 1)->atttypid;
	tw->tiletypmod = TupleDescAttr(desc, 1)->atttypmod;
}

/*
 * Ready the rows: triangles of dim (2 or 3) doubles a vertex with this
 * SRID.  A typmod on the geometry column must agree on both (PostGIS's
 * layout: the SRID in bits 8 to 28, signed by bit 28, Z in bit 1): the
 * caller made the column from the source's first row, and the rows read
 * since must not have changed that.
 */
void
tdc_table_writer_shape(TdcTableWriter *tw, int dim, int32 srid, const char *fname)
{
	int32		typmod = TupleDescAttr(RelationGetDescr(tw->rel), 2)->atttypmod;

	if (typmod >= 0)
	{
		int32		tsrid = ((typmod & 0x0FFFFF00) - (typmod & 0x10000000)) >> 8;
		bool		tz = (typmod & 0x00000002) != 0;

		if (tsrid != srid || tz != (dim == 3))
			ereport(ERROR,
					(errcode(ERRCODE_DATATYPE_MISMATCH),
					 errmsg("%s: the rows read have SRID %d%s, the target's column SRID %d%s",
							fname, srid, dim == 3 ? " and Z" : "", tsrid, tz ? " and Z" : ""),
					 errhint("The source changed while it was read; call again.")));
	}
	tw->slots = palloc(sizeof(TupleTableSlot *) * TW_BATCH);
	tw->geoms = palloc(sizeof(struct varlena *) * TW_BATCH);
	/*
	 * The table AM's own slots: a heap slot forms its tuple in its own
	 * memory, freed when it is cleared (a virtual slot's tuple would be
	 * copied into the current context, and kept there to the end).
	 */
	for (int i = 0; i < TW_BATCH; i++)
	{
		tw->slots[i] = table_slot_create(tw->rel, NULL);
		tw->geoms[i] = palloc(tdc_gser_triangle_size(dim == 3));
	}
	tw->batch_cxt = AllocSetContextCreate(CurrentMemoryContext, "tdc table writer batch",
										  ALLOCSET_DEFAULT_SIZES);
	tw->bistate = GetBulkInsertState();
	tw->cid = GetCurrentCommandId(true);
	tw->dim = dim;
	tw->srid = srid;
}

/* The batch so far into the table. */
static void
flush_batch(TdcTableWriter *tw)
{
	MemoryContext old;

	if (tw->nbatch == 0)
		return;
	/* whatever the insert allocates goes with the batch */
	old = MemoryContextSwitchTo(tw->batch_cxt);
	table_multi_insert(tw->rel, tw->slots, tw->nbatch, tw->cid, TABLE_INSERT_SKIP_FSM, tw->bistate);
	MemoryContextSwitchTo(old);
	for (int i = 0; i < tw->nbatch; i++)
		ExecClearTuple(tw->slots[i]);
	MemoryContextReset(tw->batch_cxt);
	tw->nbatch = 0;
	CHECK_FOR_INTERRUPTS();
}

/*
 * One row: the triangle of the three vertices at v (dim doubles each), its
 * tile a value of the tile column's type that stays valid until the
 * writer is closed.
 */
void
tdc_table_writer_put(TdcTableWriter *tw, int64 id, Datum tile, const double *v)
{
	TupleTableSlot *slot = tw->slots[tw->nbatch];
	struct varlena *g = tw->geoms[tw->nbatch];

	/* the tuples are formed when the batch goes in: each row has its own value */
	tdc_gser_write_triangle_coords(g, v, tw->dim, tw->srid);
	slot->tts_values[0] = Int64GetDatum(id);
	slot->tts_values[1] = tile;
	slot->tts_values[2] = PointerGetDatum(g);
	slot->tts_isnull[0] = slot->tts_isnull[1] = slot->tts_isnull[2] = false;
	ExecStoreVirtualTuple(slot);
	tw->rows++;
	if (++tw->nbatch == TW_BATCH)
		flush_batch(tw);
}

/* The last batch in, the bulk insert finished; the lock stays until the transaction ends. */
void
tdc_table_writer_close(TdcTableWriter *tw)
{
	if (tw->slots != NULL)
	{
		flush_batch(tw);
		for (int i = 0; i < TW_BATCH; i++)
			ExecDropSingleTupleTableSlot(tw->slots[i]);
		FreeBulkInsertState(tw->bistate);
		table_finish_bulk_insert(tw->rel, TABLE_INSERT_SKIP_FSM);
	}
	table_close(tw->rel, NoLock);
	tw->rel = NULL;
}
