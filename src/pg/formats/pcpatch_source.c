/*
 * pcpatch_source.c
 *		pgpointcloud patches as the input of the aggregates: each patch's
 *		X, Y and Z appended to the state's point buffer, as the geometry
 *		path appends a geometry's vertices.
 *
 * The pcpatch overloads of ST_TDCDelaunay, ST_TDCContours, ST_TDCDrape and
 * ST_TDCInterpolate (extension tdc_delaunay_pointcloud) have transition
 * functions that differ from the geometry ones only in calling
 * tdc_pc_read_patch instead of the geometry reader, so the vertices, in
 * the same order, reach the same final function: the results are the
 * geometry path's, byte for byte.
 *
 * The format of a pcid (its schema XML and SRID) is read from
 * pointcloud_formats, in the schema where the pointcloud extension lives,
 * once per aggregate call site in a query (the last pcid's format kept in
 * its flinfo's fn_extra, as pgpointcloud keeps its schemas), and copied
 * into each state with the parsed filter: read once per state, two SPI
 * queries and the XML took 45 us a group, which made a GROUP BY of patches
 * of 3 points slower than PC_Explode into the geometry aggregate.  A
 * query sees one snapshot of the table, so its groups share the format.
 * One aggregate takes one pcid: patches of two formats could hold X in
 * different units or meanings, and the SRID comes with the format.  The
 * pcpatch aggregates have no combine function (no partial aggregation), so
 * that this check covers every row.
 *
 * The tiled procedures read a pcpatch column through the same function
 * (tdc_pc_append_patch, from dump_query.c), their format kept in the call
 * rather than in a state, only when called through the forms of their
 * internal functions that tdc_delaunay_pointcloud declares.
 *
 * The bytes are decoded by pcpatch_read.c (pure C, fuzzed); this file maps
 * its codes to errors with hints.  Once the layout is found able to hold
 * the header's point count (tdc_pc_patch_check), the buffer grows by it
 * under tdc_delaunay.max_memory and the decoded points go straight into
 * it (only the filtered ones stay); the decoder's scratch (16 bytes a
 * point of the patch) counts against the limit while it lives.
 */
#include "postgres.h"

#include "catalog/pg_type.h"
#include "commands/extension.h"
#include "executor/spi.h"
#include "utils/builtins.h"
#include "utils/lsyscache.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "formats/pcpatch_format.h"

typedef struct TdcPcSource
{
	uint32		pcid;
	int32		srid;
	char	   *filter_text;	/* as given; NULL: none */
	TdcPcSchema schema;
	TdcPcFilter filter;
} TdcPcSource;

/* The filter argument: the one after the geometry signature's last. */
text *
tdc_pc_filter_arg(FunctionCallInfo fcinfo, int geometry_nargs)
{
	if (PG_NARGS() <= geometry_nargs || PG_ARGISNULL(geometry_nargs))
		return NULL;
	return PG_GETARG_TEXT_PP(geometry_nargs);
}

static void
pc_error(int rc, const char *err, uint32 pcid, const char *fname)
{
	switch (rc)
	{
		case TDC_PC_ERR_LAZ:
			ereport(ERROR,
					(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
					 errmsg("%s: pcpatch of pcid %u is LAZ-compressed, which tdc_delaunay does not read",
							fname, pcid),
					 errhint("Store the patches uncompressed or dimensional: PC_Uncompress(pa), or a format whose "
							 "compression is 'none' or 'dimensional' (Debian's pgpointcloud cannot write LAZ).")));
			break;
		case TDC_PC_ERR_NOXYZ:
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: the schema of pcid %u has no X, Y and Z", fname, pcid),
					 errdetail("%s.", err),
					 errhint("The triangulation needs dimensions named X, Y and Z (or Longitude/Lon, Latitude/Lat, "
							 "H/Height) in pointcloud_formats.")));
			break;
		case TDC_PC_ERR_SCHEMA:
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: cannot read the schema of pcid %u in pointcloud_formats", fname, pcid),
					 errdetail("%s.", err),
					 errhint("The schema must be pgpointcloud's XML: <pc:PointCloudSchema> with <pc:dimension> "
							 "elements (position, name, interpretation, scale, offset).")));
			break;
		case TDC_PC_ERR_COMPRESSION:
			ereport(ERROR,
					(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
					 errmsg("%s: pcpatch of pcid %u: %s", fname, pcid, err),
					 errhint("tdc_delaunay reads uncompressed and dimensional patches (none, run-length, "
							 "significant bits, zlib); PC_Uncompress(pa) gives one it reads.")));
			break;
		case TDC_PC_ERR_FILTER:
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: invalid pcpatch filter: %s", fname, err),
					 errhint("Write the filter as 'dimension=value[,value...]', e.g. 'Classification=2', "
							 "with a dimension of the patches' schema.")));
			break;
		case TDC_PC_ERR_NONFINITE:
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: input has a non-finite coordinate (NaN or Infinity)", fname),
					 errdetail("In a pcpatch of pcid %u: %s.", pcid, err)));
			break;
		case TDC_PC_ERR_TRUNCATED:
			ereport(ERROR,
					(errcode(ERRCODE_DATA_CORRUPTED),
					 errmsg("%s: truncated pcpatch of pcid %u: %s", fname, pcid, err),
					 errhint("The value is shorter than its header says; PC_AsText(pa) shows what pgpointcloud "
							 "reads of it.")));
			break;
		default:
			ereport(ERROR,
					(errcode(ERRCODE_DATA_CORRUPTED),
					 errmsg("%s: corrupt pcpatch of pcid %u: %s", fname, pcid, err),
					 errhint("The value is not a patch pgpointcloud wrote; PC_AsText(pa) shows what pgpointcloud "
							 "reads of it.")));
	}
}

/*
 * The format of pcid from pointcloud_formats: its SRID and its schema,
 * parsed, into src.  The table is qualified with the pointcloud
 * extension's schema, not found on the search path.
 */
static void
pc_lookup(TdcPcSource *src, uint32 pcid, const char *fname)
{
	Oid			ext = get_extension_oid("pointcloud", true);
	Oid			argtypes[1] = {INT4OID};
	Datum		args[1];
	char	   *nsp,
			   *query,
			   *xml = NULL;
	bool		isnull;
	int			rc;
	char		err[256];
	MemoryContext outer = CurrentMemoryContext;

	if (ext == InvalidOid)
		ereport(ERROR,
				(errcode(ERRCODE_UNDEFINED_OBJECT),
				 errmsg("%s: extension \"pointcloud\" is not installed", fname)));
	if (SPI_connect() != SPI_OK_CONNECT)
		elog(ERROR, "%s: SPI_connect failed", fname);
	args[0] = ObjectIdGetDatum(ext);
	rc = SPI_execute_with_args("SELECT n.nspname::text FROM pg_catalog.pg_extension e "
							   "JOIN pg_catalog.pg_namespace n ON n.oid = e.extnamespace WHERE e.oid = $1",
							   1, (Oid[]) {OIDOID}, args, NULL, true, 1);
	if (rc != SPI_OK_SELECT || SPI_processed != 1)
		elog(ERROR, "%s: the schema of extension pointcloud was not found", fname);
	nsp = TextDatumGetCString(SPI_getbinval(SPI_tuptable->vals[0], SPI_tuptable->tupdesc, 1, &isnull));
	query = psprintf("SELECT srid, schema FROM %s.pointcloud_formats WHERE pcid = $1",
					 quote_identifier(nsp));
	args[0] = Int32GetDatum((int32) pcid);
	rc = SPI_execute_with_args(query, 1, argtypes, args, NULL, true, 1);
	if (rc != SPI_OK_SELECT)
		elog(ERROR, "%s: reading pointcloud_formats failed", fname);
	if (SPI_processed == 1)
	{
		Datum		d = SPI_getbinval(SPI_tuptable->vals[0], SPI_tuptable->tupdesc, 1, &isnull);

		src->srid = isnull ? 0 : DatumGetInt32(d);
		d = SPI_getbinval(SPI_tuptable->vals[0], SPI_tuptable->tupdesc, 2, &isnull);
		if (!isnull)
		{
			MemoryContext spi = MemoryContextSwitchTo(outer);

			xml = TextDatumGetCString(d);
			MemoryContextSwitchTo(spi);
		}
	}
	rc = (int) SPI_processed;
	SPI_finish();
	if (rc != 1)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: pcid %u is not in pointcloud_formats", fname, pcid)));
	if (xml == NULL)
		pc_error(TDC_PC_ERR_SCHEMA, "the schema is NULL", pcid, fname);
	err[0] = '\0';
	rc = tdc_pc_schema_parse(xml, strlen(xml), &src->schema, err, sizeof(err));
	if (rc != TDC_PC_OK)
		pc_error(rc, err, pcid, fname);
	pfree(xml);
	src->pcid = pcid;
}

/*
 * Append the points of one patch (those passing the filter ftext, NULL:
 * none) to buf; what names the input in the mixed pcid error.  The first patch fixes the pcid and the filter, its format
 * kept in *srcp (allocated in cxt); later ones must agree.  The aggregates
 * keep *srcp in their state (tdc_pc_read_patch); the tiled procedures in
 * their call (tdc_dump_collect_pc), in a context that outlives the
 * point buffer's, which staging to files resets.
 */
void
tdc_pc_append_patch(TdcPointBuf *buf, struct TdcPcSource **srcp, MemoryContext cxt,
					FmgrInfo *flinfo, Datum patch, const char *ftext, const char *what,
					const char *fname)
{
	TdcPcSource *src = *srcp;
	struct varlena *v;
	TdcPcHeader h;
	char		err[256];
	int			rc;
	size_t		kept,
				sbytes;
	void	   *scratch;

	err[0] = '\0';
	v = PG_DETOAST_DATUM(patch);
	rc = tdc_pc_patch_header((const uint8_t *) v, VARSIZE(v), &h, err, sizeof(err));
	if (rc != TDC_PC_OK)
		pc_error(rc, err, 0, fname);
	if (src == NULL)
	{
		TdcPcSource *known = flinfo ? (TdcPcSource *) flinfo->fn_extra : NULL;

		/* the call site's format: pcid, SRID and schema, no filter */
		src = MemoryContextAllocZero(cxt, sizeof(TdcPcSource));
		if (known != NULL && known->pcid == h.pcid)
			*src = *known;
		else
		{
			pc_lookup(src, h.pcid, fname);
			if (flinfo != NULL)
			{
				if (known == NULL)
					flinfo->fn_extra = known = MemoryContextAlloc(flinfo->fn_mcxt, sizeof(TdcPcSource));
				*known = *src;
			}
		}
		if (ftext != NULL)
		{
			rc = tdc_pc_filter_parse(ftext, &src->schema, &src->filter, err, sizeof(err));
			if (rc != TDC_PC_OK)
				pc_error(rc, err, h.pcid, fname);
			src->filter_text = MemoryContextStrdup(cxt, ftext);
		}
		else
			src->filter.dim = -1;
		*srcp = src;
	}
	else if (src->pcid != h.pcid)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: patches of different pcids %u and %u in one %s",
						fname, Min(src->pcid, h.pcid), Max(src->pcid, h.pcid),
						what),
				 errhint("Take the patches of each pcid apart (WHERE PC_PCId(pa) = ...), or move them to one "
						 "format with PC_Transform.")));
	if ((ftext == NULL) != (src->filter_text == NULL) ||
		(ftext != NULL && strcmp(ftext, src->filter_text) != 0))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the pcpatch filter must be the same for all rows", fname)));

	tdc_pointbuf_check_meta(buf, src->srid, true, fname);
	/* a count the bytes cannot hold is refused before room is made for it */
	rc = tdc_pc_patch_check((const uint8_t *) v, VARSIZE(v), &src->schema, err, sizeof(err));
	if (rc != TDC_PC_OK)
		pc_error(rc, err, h.pcid, fname);
	if (h.npoints == 0)
		return;
	tdc_pointbuf_reserve(buf, h.npoints, fname);
	/* the scratch counts against the limit while it lives */
	sbytes = tdc_pc_scratch_bytes(&src->schema, h.npoints);
	tdc_pointbuf_side_grow(buf, 0, sbytes, "a patch's decoding buffer", fname);
	scratch = palloc_extended(sbytes, MCXT_ALLOC_HUGE);
	rc = tdc_pc_patch_decode((const uint8_t *) v, VARSIZE(v), &src->schema, &src->filter,
							 buf->xy + 2 * buf->n, buf->z + buf->n, scratch, &kept,
							 err, sizeof(err));
	pfree(scratch);
	tdc_pointbuf_side_grow(buf, sbytes, 0, "a patch's decoding buffer", fname);
	if (rc != TDC_PC_OK)
		pc_error(rc, err, h.pcid, fname);
	buf->n += kept;
	if ((Pointer) v != DatumGetPointer(patch))
		pfree(v);
}

/* An aggregate's row: the patch into its state, the format kept there. */
void
tdc_pc_read_patch(TdcAggState *st, FmgrInfo *flinfo, Datum patch, text *filter, const char *fname)
{
	tdc_pc_append_patch(&st->pts, &st->pc, st->pts.cxt, flinfo, patch,
						filter ? text_to_cstring(filter) : NULL, "aggregate", fname);
}
