/*
 * fn_interpolate_tiled.c
 *		tdc_interpolate_tiled: the samples of a table interpolated into a
 *		raster coverage, a table of tiles like raster2pgsql -t writes,
 *		within tdc_delaunay.max_memory: _tdc_interpolate_tiled_write.
 *
 * The procedure (src/sql/raster_tiled.sql) checks the arguments, reads the
 * band-less template's size, georeference and SRID, creates the target
 * (rid bigint, rast raster) and calls this function once.  The samples are
 * read as ST_TDCInterpolate reads them (curves by their stored vertices,
 * the first copy of a duplicate giving its height), through the staging of
 * tdc_delaunay_tiled (tiled_stage.c): in memory while the vertices, the
 * engine, the TIN and the whole grid's values fit the limit, else to files
 * for the core's bounded run.
 *
 * One pass: the TIN and tdc_tin_grid_start over the whole grid, as
 * ST_TDCInterpolate computes it (tdc_raster_interpolate), so the tiles are
 * that raster's windows, pixel for pixel, for every method.  In tiles: the
 * bounded run emits final triangles on its thread, and its callbacks hand
 * them to the core's raster (tdc_raster_begin/_tile: the same values to
 * the bit, linear and nearest, on any grid whose pixels have an area:
 * skewed, rotated or flipped too; natural neighbour takes each final
 * tile's whole triangulation instead, tdc_raster_nn_tile, which proves
 * every pixel's cavity global or has the tile run again; the core says why
 * it refuses anything else); after the run the rows come out a band of
 * tile_height rows at a time (tdc_raster_rows), what the band, a tile and
 * its value hold being taken off the tiles' budget in the begin callback.
 * The callbacks never call PostgreSQL.
 *
 * Each tile is the window (c0, r0, w, h) of the grid, numbered rid = 1..
 * row by row from the top left as raster2pgsql numbers them, the last
 * column and row of tiles cut to fit; its upper left corner is the grid's
 * pixel corner (c0, r0), gt[0] + c0 gt[1] + r0 gt[2] and gt[3] + c0 gt[4] +
 * r0 gt[5], as raster2pgsql and ST_Tile place it.  Values are stored by
 * raster_write.c as ST_TDCInterpolate stores them; a pixel without a value
 * holds the band's nodata value, and a tile whose pixels are all nodata is
 * still written (a coverage has every tile).  Rows go in through SPI, one
 * prepared INSERT per tile: tiles are few (a 65535 x 65535 grid in 256 x
 * 256 tiles is 65536 rows) and big.  The procedure and this function are
 * one transaction: an error or a cancel leaves no target.
 *
 * On Citus nothing here changes: a distributed source is one distributed
 * SELECT that the executor gathers on the coordinator, read once through
 * the same cursor, and the target is the coordinator's plain table the
 * procedure made, so the tiles are those of a plain source to the byte.
 */
#include "postgres.h"

#include <math.h>

#include "catalog/pg_type_d.h"
#include "executor/spi.h"
#include "miscadmin.h"
#include "lib/stringinfo.h"
#include "utils/array.h"
#include "utils/builtins.h"
#include "utils/lsyscache.h"
#include "utils/memutils.h"

#include "tdc_pg.h"
#include "formats/raster_format.h"
#include "fn/fn_raster.h"
#include "fn/tiled_stage.h"

#define COV_FNAME			"tdc_interpolate_tiled"

/* The coverage being written, and what the run's callbacks share. */
typedef struct Coverage
{
	StageConsumer sc;			/* first: the run's arg; its consumer the raster */
	double		gt[6];
	uint32		width,
				height,
				tw,
				th;				/* tile size, at most the grid's */
	int32		srid;
	int			pixtype;
	double		nodata;			/* as given; as stored: tdc_raster_nodata_value */
	tdc_interp_spec spec;
	double	   *tilev;			/* a tile's values, th * tw */
	uint8	   *tileok;			/* and their mask */
	SPIPlanPtr	plan;
	MemoryContext row_cxt;		/* a tile's allocations, reset after each */
	uint64		rows;
} Coverage;

/* The consumer's callbacks (tdc_stage_consumer_init): the core's raster. */
static int
coverage_tile(void *obj, const double *q, const double *qz, const size_t *tri, size_t ntri, char *err,
			  size_t errlen)
{
	return tdc_raster_tile((tdc_raster *) obj, q, qz, tri, ntri, err, errlen);
}

/* natural neighbour: the run's final_run, on its thread (the raster proves each pixel's cavity) */
static int
coverage_final_run(void *arg, const tdc_job *job, const double *q, const double *qz, size_t m,
				   const size_t *tri, size_t ntri, const tdc_tile_spec *spec, tdc_tile_result *more)
{
	StageConsumer *sc = (StageConsumer *) arg;

	return tdc_raster_nn_tile((tdc_raster *) sc->obj, job, q, qz, m, tri, ntri, spec, more, sc->err,
							  sizeof(sc->err));
}

static void
coverage_free(void *obj)
{
	tdc_raster_free((tdc_raster *) obj);
}

/* The bytes a band of rows, a tile's buffers and its raster value take. */
static uint64
coverage_buffers(const Coverage *cov, bool band)
{
	uint64		tile = (uint64) cov->tw * cov->th;

	return (band ? (uint64) cov->width * cov->th * sizeof(double) : 0) +
		tile * (sizeof(double) + 1) + tdc_raster_value_size(cov->tw, cov->th, cov->pixtype);
}

/* The run's begin, on its thread: the core's raster made, its buffers and ours held. */
static int
coverage_begin(void *arg, const double box[4], const double *hull, size_t nhull, size_t *hold)
{
	Coverage   *cov = (Coverage *) arg;
	tdc_grid_spec g;
	tdc_raster *ras = NULL;
	size_t		h = 0;
	int			rc;

	(void) box;
	memcpy(g.gt, cov->gt, sizeof(g.gt));
	g.width = cov->width;
	g.height = cov->height;
	/* one tile at a time: the consumer takes the tiles on the backend's thread */
	rc = tdc_raster_begin(&cov->spec, &g, hull, nhull, cov->sc.br->dir, 1, &ras, &h,
						  cov->sc.err, sizeof(cov->sc.err));
	cov->sc.obj = ras;
	if (rc != TDC_OK)
		return rc;
	*hold = h + (size_t) coverage_buffers(cov, true);
	return TDC_OK;
}

/*
 * The tiles of rows r0 .. r0 + nrows - 1: v holds those rows of the grid
 * (width values each), valid their mask (NULL: every pixel holds a value or
 * the stored nodata value, which stores the same bytes as a masked pixel).
 */
static void
write_band(Coverage *cov, const double *v, const uint8 *valid, uint32 r0, uint32 nrows)
{
	uint32		ncols = (cov->width + cov->tw - 1) / cov->tw;

	for (uint32 c0 = 0; c0 < cov->width; c0 += cov->tw)
	{
		TdcRasterInfo info;
		TdcRasterWriter w;
		uint32		cw = Min(cov->tw, cov->width - c0);
		Datum		args[2];
		MemoryContext old;
		int			rc;

		for (uint32 r = 0; r < nrows; r++)
		{
			memcpy(cov->tilev + (Size) r * cw, v + (Size) r * cov->width + c0, cw * sizeof(double));
			if (valid)
				memcpy(cov->tileok + (Size) r * cw, valid + (Size) r * cov->width + c0, cw);
		}
		memset(&info, 0, sizeof(info));
		info.srid = cov->srid;
		info.width = (uint16) cw;
		info.height = (uint16) nrows;
		info.gt[0] = cov->gt[0] + c0 * cov->gt[1] + r0 * cov->gt[2];
		info.gt[1] = cov->gt[1];
		info.gt[2] = cov->gt[2];
		info.gt[3] = cov->gt[3] + c0 * cov->gt[4] + r0 * cov->gt[5];
		info.gt[4] = cov->gt[4];
		info.gt[5] = cov->gt[5];
		/* the tile's value and what the insert allocates go with the row */
		old = MemoryContextSwitchTo(cov->row_cxt);
		tdc_raster_alloc(&info, cov->pixtype, cov->nodata, COV_FNAME, &w);
		tdc_raster_fill(&w, cov->tilev, valid ? cov->tileok : NULL);
		args[0] = Int64GetDatum((int64) (r0 / cov->th) * ncols + c0 / cov->tw + 1);
		args[1] = PointerGetDatum(w.value);
		rc = SPI_execute_plan(cov->plan, args, NULL, false, 0);
		if (rc != SPI_OK_INSERT)
			elog(ERROR, "%s: inserting a tile failed: %s", COV_FNAME, SPI_result_code_string(rc));
		MemoryContextSwitchTo(old);
		MemoryContextReset(cov->row_cxt);
		cov->rows++;
	}
}

/* The prepared INSERT of one tile into target (rid bigint, rast raster). */
static void
prepare_insert(Coverage *cov, Oid target)
{
	Oid			types[2] = {INT8OID, get_atttype(target, 2)};
	char	   *sql = psprintf("INSERT INTO %s (rid, rast) VALUES ($1, $2)",
							   quote_qualified_identifier(get_namespace_name(get_rel_namespace(target)),
														  get_rel_name(target)));

	cov->plan = SPI_prepare(sql, 2, types);
	if (cov->plan == NULL)
		elog(ERROR, "%s: SPI_prepare failed: %s", COV_FNAME, SPI_result_code_string(SPI_result));
}

/* Pixel type by PostGIS's name ("32BF"); an ERROR for none. */
static int
pixtype_by_name(const char *name)
{
	for (int t = 0; t < RT_PT_COUNT; t++)
		if (pg_strcasecmp(name, tdc_raster_pixtype_name(t)) == 0)
			return t;
	ereport(ERROR,
			(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
			 errmsg("%s: pixel_type \"%s\" is not a PostGIS pixel type", COV_FNAME, name),
			 errhint("Use one of 1BB, 2BUI, 4BUI, 8BSI, 8BUI, 16BSI, 16BUI, 32BSI, 32BUI, 32BF, 64BF.")));
	return -1;
}

PG_FUNCTION_INFO_V1(_tdc_interpolate_tiled_write);

/*
 * _tdc_interpolate_tiled_write(query text, target regclass, gt float8[],
 *		width int4, height int4, srid int4, method text, pixel_type text,
 *		nodata float8, tile_width int4, tile_height int4, geom_type regtype
 *		[, filter text]) RETURNS int8
 * The tiles written; see the top of this file.  nodata NULL: the method's
 * (as a template band without a nodata value).  With filter (the form
 * tdc_delaunay_pointcloud declares) the column holds pcpatch values, the
 * filter NULL or 'dimension=value[,...]'.  Internal to
 * tdc_interpolate_tiled, which checked the arguments it reports on.
 */
Datum
_tdc_interpolate_tiled_write(PG_FUNCTION_ARGS)
{
	const char *fname = COV_FNAME;
	const char *setting;
	uint64		limit_mb = tdc_memory_limit_mb(&setting);
	MemoryContext cxt = CurrentMemoryContext;
	char	   *query;
	Oid			target;
	ArrayType  *gta;
	char	   *method;
	Coverage   *cov;
	BoundedRun *br;
	TdcPointBuf buf;
	StageArg	sa;
	tdc_options opt;
	tdc_bounded_stats st;
	uint64		npts;
	Size		npix;
	int			tiles = 0;

	tdc_signal_guard();
	for (int i = 0; i < PG_NARGS(); i++)
		if (PG_ARGISNULL(i) && i != 8 && i != 12)
			ereport(ERROR,
					(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
					 errmsg("%s: argument %d must not be NULL", fname, i + 1)));
	query = text_to_cstring(PG_GETARG_TEXT_PP(0));
	target = PG_GETARG_OID(1);
	gta = PG_GETARG_ARRAYTYPE_P(2);
	if (ARR_NDIM(gta) != 1 || ArrayGetNItems(ARR_NDIM(gta), ARR_DIMS(gta)) != 6 ||
		ARR_HASNULL(gta) || ARR_ELEMTYPE(gta) != FLOAT8OID)
		elog(ERROR, "%s: the geotransform must be 6 float8", fname);

	cov = MemoryContextAllocZero(cxt, sizeof(Coverage));
	memcpy(cov->gt, ARR_DATA_PTR(gta), sizeof(cov->gt));
	if (PG_GETARG_INT32(3) < 1 || PG_GETARG_INT32(3) > PG_UINT16_MAX ||
		PG_GETARG_INT32(4) < 1 || PG_GETARG_INT32(4) > PG_UINT16_MAX ||
		PG_GETARG_INT32(9) < 1 || PG_GETARG_INT32(9) > PG_UINT16_MAX ||
		PG_GETARG_INT32(10) < 1 || PG_GETARG_INT32(10) > PG_UINT16_MAX)
		elog(ERROR, "%s: sizes out of range", fname);
	cov->width = PG_GETARG_INT32(3);
	cov->height = PG_GETARG_INT32(4);
	cov->srid = PG_GETARG_INT32(5);
	method = text_to_cstring(PG_GETARG_TEXT_PP(6));
	cov->pixtype = pixtype_by_name(text_to_cstring(PG_GETARG_TEXT_PP(7)));
	cov->tw = Min((uint32) PG_GETARG_INT32(9), cov->width);
	cov->th = Min((uint32) PG_GETARG_INT32(10), cov->height);
	tdc_raster_method(method, &cov->spec, fname);
	if (cov->spec.breaklines)
		ereport(ERROR,
				(errcode(ERRCODE_FEATURE_NOT_SUPPORTED),
				 errmsg("%s: method \"%s\": breaklines are not taken here", fname, method),
				 errhint("Interpolate with ST_TDCInterpolate, window by window.")));
	/* the band's nodata value, as ST_TDCInterpolate chooses it (fn_raster.c) */
	cov->nodata = PG_ARGISNULL(8) || tdc_raster_method_sets_nodata(method) ?
		cov->spec.nodata : PG_GETARG_FLOAT8(8);
	cov->spec.nodata = tdc_raster_nodata_value(cov->pixtype, cov->nodata);
	tdc_session_options(&opt);

	/* the files and the raster go with this call's memory, whatever ends it */
	tdc_stage_consumer_init(&cov->sc, cxt, coverage_tile, coverage_free);
	br = cov->sc.br;

	/* the samples: in memory while one pass fits, then to the files */
	npix = (Size) cov->width * cov->height;
	tdc_pointbuf_init(&buf, AllocSetContextCreate(cxt, "tdc_interpolate_tiled samples", ALLOCSET_DEFAULT_SIZES));
	buf.curves = TDC_CURVES_VERTICES;
	tdc_stage_init(&sa, br, &buf, cxt, &opt, limit_mb, fname);
	/* one pass holds the TIN, the grid's values and mask, and a tile */
	sa.tin = true;
	sa.beside = (uint64) npix * (sizeof(double) + 1) + coverage_buffers(cov, false);
	tdc_dump_collect_pc(&buf, query, PG_GETARG_OID(11), tdc_stage_pc_column(fcinfo, 12, cxt), fname,
						tdc_stage_row, &sa);
	npts = tdc_stage_done(&sa);
	if (npts > 0 && !buf.hasz)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the samples have no Z coordinate", fname),
				 errhint("Every sample needs a height: make the samples XYZ.")));

	cov->tilev = MemoryContextAllocHuge(cxt, (Size) cov->tw * cov->th * sizeof(double));
	cov->tileok = MemoryContextAllocHuge(cxt, (Size) cov->tw * cov->th);
	cov->row_cxt = AllocSetContextCreate(cxt, "tdc_interpolate_tiled tile", ALLOCSET_DEFAULT_SIZES);
	if (!sa.to_files)
	{
		/* one pass: the whole grid as ST_TDCInterpolate computes it */
		double	   *values = MemoryContextAllocHuge(cxt, Max(npix, 1) * sizeof(double));
		uint8	   *valid = MemoryContextAllocHuge(cxt, Max(npix, 1));

		if (npts > 0)
		{
			TdcTinRun  *tr = tdc_tin_run_start(&buf, NULL, sa.beside, fname);
			tdc_grid_spec grid;
			char		err[256];
			int			rc;

			memcpy(grid.gt, cov->gt, sizeof(grid.gt));
			grid.width = cov->width;
			grid.height = cov->height;
			err[0] = '\0';
			rc = tdc_tin_grid_start(tr->tin, &cov->spec, &grid, values, valid, err, sizeof(err));
			tdc_tin_run_wait(tr, rc, err, fname);
			tdc_tin_run_free(tr);
		}
		else
			memset(valid, 0, npix);
		if (SPI_connect() != SPI_OK_CONNECT)
			elog(ERROR, "%s: SPI_connect failed", fname);
		prepare_insert(cov, target);
		for (uint32 r0 = 0; r0 < cov->height; r0 += cov->th)
			write_band(cov, values + (Size) r0 * cov->width, valid + (Size) r0 * cov->width, r0,
					   Min(cov->th, cov->height - r0));
		SPI_finish();
		ereport(NOTICE,
				(errmsg("%s: %llu tiles of %u x %u pixels from %llu points, in one pass", fname,
						(unsigned long long) cov->rows, cov->tw, cov->th, (unsigned long long) npts)));
		PG_RETURN_INT64((int64) cov->rows);
	}

	/* in tiles: the run on its thread rasterises, then the bands come out */
	{
		tdc_bounded_params p;
		double	   *band;
		uint64		held;
		size_t		nvalid = 0;

		memset(&p, 0, sizeof(p));
		p.begin = coverage_begin;
		if (cov->spec.method == TDC_INTERP_NATURAL)
		{
			/* each final tile's whole triangulation instead of its triangles */
			p.final_run = coverage_final_run;
			p.final_per_point = TDC_RASTER_NN_PER_POINT;
			p.final_run_why = TDC_RASTER_NN_WHY;
		}
		else
			p.emit = tdc_stage_consumer_emit;
		p.arg = cov;
		p.any_order = true;
		/* the staging buffer, still allocated, is beside the run */
		tdc_stage_run(br, &p, &opt, limit_mb, setting, tdc_pointbuf_bytes(&buf), "tiled interpolation",
					  cov->sc.err, &st, fname);
		tiles = st.tiles;
		/* what the limit leaves beside our buffers is the fringe's, in the first band */
		held = tdc_pointbuf_bytes(&buf) + coverage_buffers(cov, true) + ((uint64) 8 << 20);
		band = MemoryContextAllocHuge(cxt, (Size) cov->width * cov->th * sizeof(double));
		if (SPI_connect() != SPI_OK_CONNECT)
			elog(ERROR, "%s: SPI_connect failed", fname);
		prepare_insert(cov, target);
		for (uint32 r0 = 0; r0 < cov->height; r0 += cov->th)
		{
			uint32		n = Min(cov->th, cov->height - r0);
			int			rc;

			CHECK_FOR_INTERRUPTS();
			cov->sc.err[0] = '\0';
			rc = tdc_raster_rows((tdc_raster *) cov->sc.obj, r0, n, band, &nvalid,
								 (size_t) (sa.limit > held ? sa.limit - held : 0), cov->sc.err, sizeof(cov->sc.err));
			if (rc != TDC_OK)
				tdc_report_status(rc, cov->sc.err, fname);
			write_band(cov, band, NULL, r0, n);
		}
		SPI_finish();
		tdc_stage_consumer_release(&cov->sc);
	}
	ereport(NOTICE,
			(errmsg("%s: %llu tiles of %u x %u pixels from %llu points in %d run tile%s under %s = %llu MB, "
					"%zu tile run%s, %zu halo points",
					fname, (unsigned long long) cov->rows, cov->tw, cov->th, (unsigned long long) npts,
					tiles, tiles == 1 ? "" : "s", setting, (unsigned long long) limit_mb,
					st.runs, st.runs == 1 ? "" : "s", st.halo)));
	PG_RETURN_INT64((int64) cov->rows);
}
