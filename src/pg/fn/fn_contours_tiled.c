/*
 * fn_contours_tiled.c
 *		tdc_contours_tiled: the contour lines of a table's samples into a
 *		table of lines, within tdc_delaunay.max_memory:
 *		_tdc_contours_tiled_write.
 *
 * The procedure (src/sql/contours_tiled.sql) checks the arguments, creates the
 * target (id bigint, level float8, geom geometry(LineStringZ, srid)) and
 * calls this function once.  The samples are read as ST_TDCContours reads
 * them (curves stroked, the first copy of a duplicate giving its height),
 * through the staging of tdc_delaunay_tiled (tiled_stage.c): in memory
 * while the vertices, the engine and the TIN fit the limit, else to files
 * for the core's bounded run.
 *
 * One pass: the TIN and its contours, as ST_TDCContours computes them
 * (tdc_tin_contours_start_spec, linear).  In tiles: the bounded run emits
 * final triangles on its thread and its callbacks cut them into pieces of
 * lines (tdc_contour_tiles_begin/_tile, the core's contour_tiles.c: the
 * same lines, the same points to the bit, in the same order); after the run
 * the pieces are joined, and as the join hands over each line (a callback
 * inside the core, which must not raise a PostgreSQL error) it is appended
 * to a file, read back once the join is done.  Either way each line becomes
 * a row, id 1.. in the lines' order (levels increasing, a level's lines by
 * their points), its vertices with the level as Z, through a prepared
 * INSERT of the geometry its EWKB gives (the type's binary input): the
 * same LINESTRING Z as the line of ST_TDCContours's MULTILINESTRING Z.
 * The procedure and this function are one transaction: an error or a
 * cancel leaves no target.
 *
 * On Citus a distributed source is read by one distributed SELECT,
 * gathered on the coordinator, and the lines go into the coordinator's
 * plain table the procedure made: the same rows as from a plain source.
 */
#include "postgres.h"

#include <errno.h>
#include <math.h>

#include "catalog/pg_type_d.h"
#include "executor/spi.h"
#include "lib/stringinfo.h"
#include "miscadmin.h"
#include "utils/builtins.h"
#include "utils/lsyscache.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "fn/tiled_stage.h"

#define CT_FNAME			"tdc_contours_tiled"

/* A line's record in the lines file: then n x,y pairs. */
typedef struct LineRecord
{
	double		level;
	uint64		n;
} LineRecord;

typedef struct ContourRun
{
	StageConsumer sc;			/* first: the run's arg; its consumer the line pieces */
	double		interval,
				base;
	tdc_interp_spec spec;
	int32		srid;
	SPIPlanPtr	plan;
	Oid			recv,			/* the geometry type's binary input */
				ioparam;
	MemoryContext row_cxt;		/* a row's allocations, reset after each */
	bytea	   *wkb;			/* a line's EWKB, grown as needed */
	uint64		wkb_cap;
	uint64		rows;
} ContourRun;

/* The consumer's callbacks (tdc_stage_consumer_init): the core's line pieces. */
static int
contour_tile(void *obj, const double *q, const double *qz, const size_t *tri, size_t ntri, char *err,
			 size_t errlen)
{
	return tdc_contour_tiles_tile((tdc_contour_tiles *) obj, q, qz, tri, ntri, err, errlen);
}

static void
contour_free(void *obj)
{
	tdc_contour_tiles_free((tdc_contour_tiles *) obj);
}

/* The run's begin, on its thread: the core's line pieces, their buffers held. */
static int
contour_begin(void *arg, const double box[4], const double *hull, size_t nhull, size_t *hold)
{
	ContourRun *cr = (ContourRun *) arg;
	tdc_contour_tiles *ct = NULL;
	int			rc;

	(void) box;
	(void) hull;
	(void) nhull;
	/* one tile at a time: the consumer takes the tiles on the backend's thread */
	rc = tdc_contour_tiles_begin(cr->interval, cr->base, &cr->spec, cr->sc.br->dir, 1, &ct, hold,
								 cr->sc.err, sizeof(cr->sc.err));
	cr->sc.obj = ct;
	return rc;
}

/* The join's callback, inside the core: a line appended to the lines file. */
static int
contour_line_out(void *arg, double level, const double *xy, size_t n, bool closed)
{
	BoundedRun *br = (BoundedRun *) arg;
	LineRecord	rec = {level, n};

	(void) closed;
	if (fwrite(&rec, sizeof(rec), 1, br->ftri) != 1 ||
		fwrite(xy, 2 * sizeof(double), n, br->ftri) != n)
	{
		br->write_errno = errno ? errno : EIO;
		return TDC_EIO;
	}
	return 0;
}

/* One line into the target: id, level, and the geometry of its EWKB (LINESTRING Z with the SRID). */
static void
put_line(ContourRun *cr, double level, const double *xy, size_t n)
{
	uint64		size = VARHDRSZ + 1 + 4 + 4 + 4 + (uint64) n * 3 * sizeof(double);
	char	   *p;
	uint32		type = 2 | 0x80000000 | 0x20000000;	/* LINESTRING, Z, SRID (EWKB) */
	uint32		npts = (uint32) n;
	Datum		args[3];
	MemoryContext old;
	int			rc;

	if (size > MaxAllocSize)
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: a contour line of %zu points is too long for a value", CT_FNAME, n)));
	if (size > cr->wkb_cap)
	{
		cr->wkb = repalloc(cr->wkb, size);
		cr->wkb_cap = size;
	}
	SET_VARSIZE(cr->wkb, size);
	p = VARDATA(cr->wkb);
#ifdef WORDS_BIGENDIAN
	*p++ = 0;
#else
	*p++ = 1;
#endif
	memcpy(p, &type, 4);
	memcpy(p + 4, &cr->srid, 4);
	memcpy(p + 8, &npts, 4);
	p += 12;
	for (size_t k = 0; k < n; k++)
	{
		memcpy(p, xy + 2 * k, 2 * sizeof(double));
		memcpy(p + 2 * sizeof(double), &level, sizeof(double));
		p += 3 * sizeof(double);
	}
	args[0] = Int64GetDatum((int64) cr->rows + 1);
	args[1] = Float8GetDatum(level);
	/* what the input function and the insert allocate goes with the row */
	old = MemoryContextSwitchTo(cr->row_cxt);
	{
		StringInfoData si;

		/* the geometry type's binary input reads EWKB: no cast by name */
		si.data = VARDATA(cr->wkb);
		si.len = (int) (size - VARHDRSZ);
		si.maxlen = si.len;
		si.cursor = 0;
		args[2] = OidReceiveFunctionCall(cr->recv, &si, cr->ioparam, -1);
	}
	rc = SPI_execute_plan(cr->plan, args, NULL, false, 0);
	if (rc != SPI_OK_INSERT)
		elog(ERROR, "%s: inserting a line failed: %s", CT_FNAME, SPI_result_code_string(rc));
	MemoryContextSwitchTo(old);
	MemoryContextReset(cr->row_cxt);
	cr->rows++;
}

/* The prepared INSERT of one line into target (id, level, geom). */
static void
prepare_insert(ContourRun *cr, Oid target)
{
	Oid			types[3] = {INT8OID, FLOAT8OID, get_atttype(target, 3)};
	char	   *sql = psprintf("INSERT INTO %s (id, level, geom) VALUES ($1, $2, $3)",
							   quote_qualified_identifier(get_namespace_name(get_rel_namespace(target)),
														  get_rel_name(target)));

	getTypeBinaryInputInfo(types[2], &cr->recv, &cr->ioparam);

	if (SPI_connect() != SPI_OK_CONNECT)
		elog(ERROR, "%s: SPI_connect failed", CT_FNAME);
	cr->plan = SPI_prepare(sql, 3, types);
	if (cr->plan == NULL)
		elog(ERROR, "%s: SPI_prepare failed: %s", CT_FNAME, SPI_result_code_string(SPI_result));
}

/* The lines file into the target. */
static void
write_lines_from_file(ContourRun *cr, const char *fname)
{
	BoundedRun *br = cr->sc.br;
	LineRecord	rec;
	double	   *xy = NULL;
	uint64		cap = 0;

	br->ftri = tdc_stage_open(br->tripath, "rb", fname);
	while (fread(&rec, sizeof(rec), 1, br->ftri) == 1)
	{
		if (rec.n > cap)
		{
			cap = rec.n;
			xy = xy ? repalloc_huge(xy, cap * 2 * sizeof(double)) :
				MemoryContextAllocHuge(CurrentMemoryContext, cap * 2 * sizeof(double));
		}
		if (rec.n > 0 && fread(xy, 2 * sizeof(double), rec.n, br->ftri) != rec.n)
			ereport(ERROR,
					(errcode(ERRCODE_INTERNAL_ERROR),
					 errmsg("%s: file \"%s\" ends early", fname, br->tripath)));
		put_line(cr, rec.level, xy, rec.n);
	}
	if (ferror(br->ftri))
		ereport(ERROR,
				(errcode_for_file_access(),
				 errmsg("%s: could not read file \"%s\": %m", fname, br->tripath)));
	tdc_stage_close(&br->ftri);
}

PG_FUNCTION_INFO_V1(_tdc_contours_tiled_write);

/*
 * _tdc_contours_tiled_write(query text, target regclass, interval float8,
 *		base float8, geom_type regtype [, filter text]) RETURNS int8
 * The lines written; see the top of this file.  With filter (the form
 * tdc_delaunay_pointcloud declares) the column holds pcpatch values.  Internal to
 * tdc_contours_tiled, which checked the arguments.
 */
Datum
_tdc_contours_tiled_write(PG_FUNCTION_ARGS)
{
	const char *fname = CT_FNAME;
	const char *setting;
	uint64		limit_mb = tdc_memory_limit_mb(&setting);
	MemoryContext cxt = CurrentMemoryContext;
	char	   *query;
	Oid			target;
	ContourRun *cr;
	BoundedRun *br;
	TdcPointBuf buf;
	StageArg	sa;
	tdc_options opt;
	tdc_bounded_stats st;
	uint64		npts;

	tdc_signal_guard();
	for (int i = 0; i < PG_NARGS(); i++)
		if (PG_ARGISNULL(i) && i != 5)
			ereport(ERROR,
					(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
					 errmsg("%s: argument %d must not be NULL", fname, i + 1)));
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	target = PG_GETARG_OID(1);
	cr = MemoryContextAllocZero(cxt, sizeof(ContourRun));
	cr->interval = PG_GETARG_FLOAT8(2);
	cr->base = PG_GETARG_FLOAT8(3);
	if (!(cr->interval > 0) || isinf(cr->interval) || !isfinite(cr->base))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: interval must be finite and > 0 and base finite, not %g and %g",
						fname, cr->interval, cr->base)));
	cr->spec.method = TDC_INTERP_LINEAR;
	tdc_session_options(&opt);

	tdc_stage_consumer_init(&cr->sc, cxt, contour_tile, contour_free);
	br = cr->sc.br;

	tdc_pointbuf_init(&buf, AllocSetContextCreate(cxt, "tdc_contours_tiled samples", ALLOCSET_DEFAULT_SIZES));
	buf.curves = TDC_CURVES_STROKE;
	tdc_stage_init(&sa, br, &buf, cxt, &opt, limit_mb, fname);
	sa.tin = true;
	tdc_dump_collect_pc(&buf, query, PG_GETARG_OID(4), tdc_stage_pc_column(fcinfo, 5, cxt), fname,
						tdc_stage_row, &sa);
	npts = tdc_stage_done(&sa);
	cr->srid = buf.srid;
	if (npts > 0 && !buf.hasz)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the samples have no Z coordinate", fname),
				 errhint("Every sample needs a height: make the samples XYZ.")));
	cr->wkb_cap = 1024;
	cr->wkb = MemoryContextAlloc(cxt, cr->wkb_cap);
	cr->row_cxt = AllocSetContextCreate(cxt, "tdc_contours_tiled row", ALLOCSET_DEFAULT_SIZES);

	if (!sa.to_files)
	{
		/* one pass: ST_TDCContours's lines */
		if (npts > 0)
		{
			TdcTinRun  *tr = tdc_tin_run_start(&buf, NULL, 0, fname);
			char		err[256];
			size_t		nlines,
						np;
			int			rc;

			err[0] = '\0';
			rc = tdc_tin_contours_start_spec(tr->tin, cr->interval, cr->base, &cr->spec, err, sizeof(err));
			tdc_tin_run_wait(tr, rc, err, fname);
			nlines = tdc_tin_contour_count(tr->tin, &np);
			prepare_insert(cr, target);
			for (size_t i = 0; i < nlines; i++)
			{
				double		level;
				size_t		n;
				bool		closed;
				const double *xy = tdc_tin_contour_line(tr->tin, i, &level, &n, &closed);

				put_line(cr, level, xy, n);
			}
			SPI_finish();
			tdc_tin_run_free(tr);
		}
		ereport(NOTICE,
				(errmsg("%s: %llu lines from %llu points, in one pass", fname,
						(unsigned long long) cr->rows, (unsigned long long) npts)));
		PG_RETURN_INT64((int64) cr->rows);
	}

	{
		tdc_bounded_params p;
		uint64		held;
		size_t		nlines = 0,
					np = 0;
		int			rc;

		memset(&p, 0, sizeof(p));
		p.begin = contour_begin;
		p.emit = tdc_stage_consumer_emit;
		p.arg = cr;
		p.any_order = true;
		tdc_stage_run(br, &p, &opt, limit_mb, setting, tdc_pointbuf_bytes(&buf), "tiled contours",
					  cr->sc.err, &st, fname);
		/* the join gets what the limit leaves beside the staging buffer and a margin */
		held = tdc_pointbuf_bytes(&buf) + ((uint64) 8 << 20);
		snprintf(br->tripath, sizeof(br->tripath), "%s/lines", br->dir);
		br->ftri = tdc_stage_open(br->tripath, "wb", fname);
		cr->sc.err[0] = '\0';
		rc = tdc_contour_tiles_lines((tdc_contour_tiles *) cr->sc.obj, (size_t) (sa.limit > held ? sa.limit - held : 0),
									 contour_line_out, br, NULL, &nlines, &np, cr->sc.err, sizeof(cr->sc.err));
		if (rc != TDC_OK)
		{
			tdc_stage_write_error(br, fname);
			tdc_report_status(rc, cr->sc.err, fname);
		}
		tdc_stage_finish(&br->ftri, br->tripath, fname);
		contour_free(cr->sc.obj);
		cr->sc.obj = NULL;
		prepare_insert(cr, target);
		write_lines_from_file(cr, fname);
		SPI_finish();
		tdc_stage_consumer_release(&cr->sc);
	}
	ereport(NOTICE,
			(errmsg("%s: %llu lines from %llu points in %d run tile%s under %s = %llu MB, "
					"%zu tile run%s, %zu halo points",
					fname, (unsigned long long) cr->rows, (unsigned long long) npts,
					st.tiles, st.tiles == 1 ? "" : "s", setting, (unsigned long long) limit_mb,
					st.runs, st.runs == 1 ? "" : "s", st.halo)));
	PG_RETURN_INT64((int64) cr->rows);
}
