/*
 * fn_tiled_region.c
 *		The known region of a tdc_delaunay_tiled tile (src/sql/tiled.sql)
 *		from the core's policy (src/core/tiles/tile_plan.c): the labels of
 *		squares of tile_size, a tile's first region, and its growth on a
 *		rerun.
 *
 * The procedure used to repeat the policy in PL/pgSQL (a halo of 8
 * spacings, hull bands of 16, K "grown by a tenth", a uniform grid of
 * squares labelled floor(x / size) * 2^32 + floor(y / size), which
 * overflowed bigint far from the origin) and had drifted from ./tdc's.  Now
 * every number comes from tile_plan.c, the file ./tdc --max-memory calls,
 * through these small helpers.  (Automatic tiles do not come here: they run
 * through the core's bounded run, fn_tiled_bounded.c.)
 *
 * A tile's known region travels as one float8[]: {h, K (4 values), the
 * extra known boxes (4 values each)}, h being the tile's halo, which the
 * growth on a rerun is measured in.
 */
#include "postgres.h"

#include "fmgr.h"
#include "funcapi.h"
#include "miscadmin.h"
#include "catalog/pg_type.h"
#include "utils/array.h"
#include "utils/builtins.h"
#include "utils/memutils.h"

#include <math.h>

#include "tdc_pg.h"
#include "tiles/tile_plan.h"



/*
 * A float8[] argument as doubles, copied (aligned); n its length.  NULLs,
 * more dimensions or too few values are errors.
 */
static double *
tdc_tiled_float8_array(ArrayType *a, int *n, int want_min, int multiple, const char *what)
{
	double	   *out;
	int			count;

	if (ARR_NDIM(a) > 1 || ARR_ELEMTYPE(a) != FLOAT8OID || ARR_HASNULL(a))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s must be a one-dimensional float8 array without NULLs",
						TILED_FNAME, what)));
	count = ARR_NDIM(a) == 0 ? 0 : ARR_DIMS(a)[0];
	if (count < want_min || count % multiple != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s has %d values, want a multiple of %d, at least %d",
						TILED_FNAME, what, count, multiple, want_min)));
	out = palloc(sizeof(double) * (count + 1));
	if (count > 0)
		memcpy(out, ARR_DATA_PTR(a), sizeof(double) * count);
	*n = count;
	return out;
}

static ArrayType *
tdc_tiled_float8_result(const double *v, int n)
{
	Datum	   *d = palloc(sizeof(Datum) * (n + 1));

	for (int i = 0; i < n; i++)
		d[i] = Float8GetDatum(v[i]);
	return construct_array(d, n, FLOAT8OID, 8, FLOAT8PASSBYVAL, TYPALIGN_DOUBLE);
}

/* A box argument {xmin, ymin, xmax, ymax}. */
static void
tdc_tiled_box_arg(ArrayType *a, double box[4], const char *what)
{
	int			n;
	double	   *v = tdc_tiled_float8_array(a, &n, 4, 4, what);

	if (n != 4)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s must be {xmin, ymin, xmax, ymax}", TILED_FNAME, what)));
	memcpy(box, v, 4 * sizeof(double));
}

/*
 * The label of the square of side size that holds (x, y), counted from the
 * origin (tdc_tp_square_label): column * 2^32 + row.  An ERROR when the
 * point lies below the origin, or its column or row passes 2^31 - 1.
 */
int64
tdc_tiled_square_label(double x, double y, const double origin[2], double size)
{
	int64_t		label;

	if (!tdc_tp_square_label(x, y, origin, size, &label))
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: the point (%.17g %.17g) has no square of tile_size %.17g counted from (%.17g %.17g)",
						TILED_FNAME, x, y, size, origin[0], origin[1]),
				 errdetail("A square's column and row count from the data's lower left corner and must stay below 2^31."),
				 errhint("Use a larger tile_size.")));
	return (int64) label;
}

PG_FUNCTION_INFO_V1(_tdc_square_label);

/* _tdc_square_label(x, y, origin_x, origin_y, size) RETURNS int8: tdc_tiled_square_label. */
Datum
_tdc_square_label(PG_FUNCTION_ARGS)
{
	double		origin[2] = {PG_GETARG_FLOAT8(2), PG_GETARG_FLOAT8(3)};

	PG_RETURN_INT64(tdc_tiled_square_label(PG_GETARG_FLOAT8(0), PG_GETARG_FLOAT8(1), origin,
										   PG_GETARG_FLOAT8(4)));
}

/*
 * The region {h, K, bands...} of a tile whose first K and halo h are given:
 * the hull bands (tdc_tp_hull_bands over the data's mean spacing) that
 * tdc_tp_first_bands takes for it.
 */
static ArrayType *
tdc_tiled_region_result(const double K[4], double h, size_t count, const double *hull, int nhull,
						double spacing)
{
	double	   *bands = palloc(sizeof(double) * 4 * (nhull + 1)),
			   *out = palloc(sizeof(double) * (5 + 4 * (nhull + 1)));
	uint8	   *mark = palloc0(nhull + 1);
	int			n = 5;

	out[0] = h;
	memcpy(out + 1, K, 4 * sizeof(double));
	tdc_tp_hull_bands(hull, (size_t) nhull, spacing, bands);
	tdc_tp_first_bands(K, count, bands, (size_t) nhull, mark);
	for (int i = 0; nhull > 1 && i < nhull; i++)
		if (mark[i])
		{
			memcpy(out + n, bands + 4 * i, 4 * sizeof(double));
			n += 4;
		}
	return tdc_tiled_float8_result(out, n);
}

PG_FUNCTION_INFO_V1(_tdc_tile_region);

/*
 * _tdc_tile_region(box float8[], n int8, extent float8[], npts int8,
 *					hull float8[]) RETURNS float8[]
 * The first known region {h, K, bands...} of a tile of n points whose box
 * is box, in data of npts points with box extent and convex hull hull
 * {x,y,...}: K is the box plus a halo of 8 of the tile's mean spacings,
 * the bands those of the hull edges near K (tdc_tp_first_known,
 * tdc_tp_first_bands).
 */
Datum
_tdc_tile_region(PG_FUNCTION_ARGS)
{
	double		box[4],
				extent[4],
				K[4],
				h,
			   *hull;
	int64		n = PG_GETARG_INT64(1),
				npts = PG_GETARG_INT64(3);
	int			nhull;

	tdc_tiled_box_arg(PG_GETARG_ARRAYTYPE_P(0), box, "the tile's box");
	tdc_tiled_box_arg(PG_GETARG_ARRAYTYPE_P(2), extent, "the extent");
	hull = tdc_tiled_float8_array(PG_GETARG_ARRAYTYPE_P(4), &nhull, 0, 2, "the hull");
	if (n < 0 || npts < 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: negative point counts", TILED_FNAME)));
	tdc_tp_first_known(box, (size_t) n, tdc_tp_spacing(extent, (size_t) npts), K, &h);
	PG_RETURN_ARRAYTYPE_P(tdc_tiled_region_result(K, h, (size_t) n, hull, nhull / 2,
												  tdc_tp_spacing(extent, (size_t) npts)));
}

PG_FUNCTION_INFO_V1(_tdc_tile_regrow);

/*
 * _tdc_tile_regrow(region float8[], need geometry, extent float8[],
 *					npts int8, hull float8[]) RETURNS float8[]
 * The region of a tile's next run, after a run that was not final: need is
 * the row _tdc_tile_triangles gave for it, a POLYGON whose ring is the box
 * it needs.  As ./tdc grows a tile that named no cell: the bands of the
 * hull edges that meet the box and that it lacks, if there are such
 * (tdc_tp_grow_bands); else K grown to the box and half the halo beyond
 * (tdc_tp_grow_known).
 */
Datum
_tdc_tile_regrow(PG_FUNCTION_ARGS)
{
	double	   *region,
				need[4],
				extent[4],
			   *hull,
			   *bands,
			   *extra,
				K[4],
				Kmin[4];
	uint8	   *inband;
	int			nregion,
				nhull;
	size_t		nextra;
	int64		npts = PG_GETARG_INT64(3);
	TdcPointBuf ring;

	region = tdc_tiled_float8_array(PG_GETARG_ARRAYTYPE_P(0), &nregion, 5, 1, "the region");
	if ((nregion - 5) % 4 != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: a region is {h, xmin, ymin, xmax, ymax, boxes...}", TILED_FNAME)));
	tdc_pointbuf_init(&ring, CurrentMemoryContext);
	(void) tdc_read_geometry(&ring, PG_GETARG_DATUM(1), TILED_FNAME);
	if (ring.n != 5)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the box needed must be a ring of 5 vertices", TILED_FNAME)));
	/* the box: corners 0 and 2 */
	need[0] = ring.xy[0];
	need[1] = ring.xy[1];
	need[2] = ring.xy[4];
	need[3] = ring.xy[5];
	tdc_tiled_box_arg(PG_GETARG_ARRAYTYPE_P(2), extent, "the extent");
	hull = tdc_tiled_float8_array(PG_GETARG_ARRAYTYPE_P(4), &nhull, 0, 2, "the hull");
	nhull /= 2;
	nextra = (nregion - 5) / 4;
	extra = palloc(sizeof(double) * (5 + 4 * (nextra + nhull + 1)));
	memcpy(extra, region, sizeof(double) * nregion);
	bands = palloc(sizeof(double) * 4 * (nhull + 1));
	inband = palloc0(nhull + 1);
	tdc_tp_hull_bands(hull, (size_t) nhull, tdc_tp_spacing(extent, (size_t) Max(npts, 0)), bands);
	/* the bands the tile has: the same doubles, made by the same call */
	for (int i = 0; nhull > 1 && i < nhull; i++)
		for (size_t e = 0; e < nextra; e++)
			if (memcmp(bands + 4 * i, region + 5 + 4 * e, 4 * sizeof(double)) == 0)
				inband[i] = 1;
	if (tdc_tp_grow_bands(bands, (size_t) nhull, need, inband, extra + 5, &nextra) > 0)
		PG_RETURN_ARRAYTYPE_P(tdc_tiled_float8_result(extra, 5 + 4 * (int) nextra));
	memcpy(K, region + 1, sizeof(K));
	tdc_tp_grow_known(K, Kmin, need, region[0]);
	memcpy(extra + 1, K, sizeof(K));
	PG_RETURN_ARRAYTYPE_P(tdc_tiled_float8_result(extra, nregion));
}
