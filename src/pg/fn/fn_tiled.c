/*
 * fn_tiled.c
 *		The per-tile step of tdc_delaunay_tiled's rounds on Citus
 *		(src/sql/tiled.sql): an aggregate that triangulates one tile with
 *		its halo and keeps the tile's final triangles
 *		(src/core/tiles/tile_final.c), and a set-returning function that
 *		unnests its result into POLYGON rows.  (On plain PostgreSQL a tile
 *		column only labels the triangles of one C function,
 *		fn_tiled_bounded.c.)
 *
 * Why an aggregate.  The procedure's per-tile work must be one statement
 * that Citus can push down to the workers when the tables are distributed
 * by the tile column:
 *
 *	INSERT INTO target
 *	SELECT ... FROM (SELECT tile, _tdc_tile(g, label, self, known, hull,
 *											  extra, seq, vi) AS r
 *					 FROM halo JOIN tiles USING (tile) GROUP BY tile) s,
 *		 LATERAL _tdc_tile_triangles(s.r) t
 *
 * A GROUP BY on the distribution column runs whole on the shard that holds
 * the group, so the points and the triangles stay on the worker.
 *
 * The aggregate's result is a bytea in the format below, not a geometry
 * collection, because a tile that is not final yet must report the box it
 * needs instead of triangles: _tdc_tile_triangles then returns one row with
 * k = 0 and that box as a POLYGON, which the procedure reads back (the
 * coordinates are the core's doubles, written and read without rounding),
 * deletes, and reruns the tile with a grown halo.
 *
 *	TileOut header, then for a final tile ntri triangles of 3 vertices of
 *	2 (XY) or 3 (XYZ) doubles, counter-clockwise.
 *
 * Ownership, Z and duplicates.  Every halo row carries the label of the
 * tile that owns the point; the core keeps a triangle in the tile owning
 * its smallest vertex.  Every row also carries its source position
 * (seq, vi); the final function sorts the rows back into that order, and
 * the core names each vertex by the first point with its coordinates, so a
 * vertex's Z is that of its first copy in the source, as in
 * ST_TDCDelaunayDump.
 *
 * _tdc_curve_to_line, at the end, is the procedure's way to read curve rows
 * as the Delaunay functions read them (curves.c strokes them).
 */
#include "postgres.h"

#include "fmgr.h"
#include "funcapi.h"
#include "miscadmin.h"
#include "utils/array.h"
#include "utils/builtins.h"
#include "utils/memutils.h"
#include "catalog/pg_type.h"

#include <math.h>

#include "tdc_pg.h"
#include "formats/gser_format.h"


/* The aggregate's transition state: the tile's points with their owners. */
typedef struct TileState
{
	TdcPointBuf pts;
	int64	   *label;			/* label_cap entries: owner of each vertex */
	int64	   *key;			/* 2 * label_cap: (seq, vi), its source order */
	uint64		label_cap;
	bool		unordered;		/* keys arrived out of source order */
	int64		self;
	double		known[4];
	double	   *hull;			/* nhull x,y */
	int			nhull;
	double	   *extra;			/* nextra boxes */
	int			nextra;
} TileState;

/* Header of the aggregate's bytea result. */
typedef struct TileOut
{
	int32		vl_len_;
	int32		final;			/* 1: triangles follow; 0: need is the box to rerun with */
	int32		srid;
	int32		hasz;
	double		need[4];
	uint64		ntri;			/* not final: 0 */
} TileOut;

static void
read_box_array(ArrayType *a, double **out, int *n, int want_min, const char *what)
{
	Datum	   *elems;
	bool	   *nulls;
	int			count;

	if (ARR_NDIM(a) > 1 || ARR_ELEMTYPE(a) != FLOAT8OID)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s must be a one-dimensional float8 array", TILED_FNAME, what)));
	deconstruct_array(a, FLOAT8OID, 8, FLOAT8PASSBYVAL, TYPALIGN_DOUBLE,
					  &elems, &nulls, &count);
	if (count < want_min || count % 2 != 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: %s has %d values, want an even number of at least %d",
						TILED_FNAME, what, count, want_min)));
	*out = palloc(sizeof(double) * count);
	for (int i = 0; i < count; i++)
	{
		if (nulls[i])
			ereport(ERROR,
					(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
					 errmsg("%s: %s contains NULL", TILED_FNAME, what)));
		(*out)[i] = DatumGetFloat8(elems[i]);
	}
	*n = count;
}

/* Compares the source positions of vertices a and b. */
static inline int
key_cmp(const int64 *key, uint64 a, uint64 b)
{
	if (key[2 * a] != key[2 * b])
		return key[2 * a] < key[2 * b] ? -1 : 1;
	if (key[2 * a + 1] != key[2 * b + 1])
		return key[2 * a + 1] < key[2 * b + 1] ? -1 : 1;
	return 0;
}

/*
 * Puts the tile's vertices back in source order.  The core names a vertex
 * by the first input point with its coordinates, so this order is what
 * makes a duplicate's Z that of its first copy in the source, as in
 * ST_TDCDelaunayDump.  Sorting here, rather than with ORDER BY in the
 * aggregate call, keeps the executor from sorting every row with all of the
 * aggregate's arguments (the hull and the boxes included): that sort spilled
 * gigabytes to disk for a tile of a million points.
 *
 * A stable bottom-up merge sort of vertex numbers, with an interrupt check
 * every SORT_POLL elements: a tile can be as big as the user's tile column
 * makes it, and qsort could not be interrupted.
 */
#define SORT_POLL	65536

static void
sort_by_source(TileState *st)
{
	uint64		n = st->pts.n;
	uint64	   *a;
	uint64	   *b;
	uint64		done = 0;
	double	   *xy;
	double	   *z = NULL;
	int64	   *label;

	if (!st->unordered || n < 2)
		return;
	a = MemoryContextAllocHuge(CurrentMemoryContext, n * sizeof(uint64));
	b = MemoryContextAllocHuge(CurrentMemoryContext, n * sizeof(uint64));
	for (uint64 i = 0; i < n; i++)
		a[i] = i;
	for (uint64 w = 1; w < n; w *= 2)
	{
		for (uint64 lo = 0; lo < n; lo += 2 * w)
		{
			uint64		mid = Min(lo + w, n);
			uint64		hi = Min(lo + 2 * w, n);
			uint64		i = lo;
			uint64		j = mid;
			uint64		k = lo;

			while (i < mid && j < hi)
				b[k++] = key_cmp(st->key, a[j], a[i]) < 0 ? a[j++] : a[i++];
			while (i < mid)
				b[k++] = a[i++];
			while (j < hi)
				b[k++] = a[j++];
			done += hi - lo;
			if (done >= SORT_POLL)
			{
				done = 0;
				CHECK_FOR_INTERRUPTS();
			}
		}
		{
			uint64	   *t = a;

			a = b;
			b = t;
		}
	}

	/* apply the permutation a to the coordinates and labels */
	xy = MemoryContextAllocHuge(CurrentMemoryContext, n * 2 * sizeof(double));
	label = MemoryContextAllocHuge(CurrentMemoryContext, n * sizeof(int64));
	if (st->pts.hasz)
		z = MemoryContextAllocHuge(CurrentMemoryContext, n * sizeof(double));
	for (uint64 i = 0; i < n; i++)
	{
		xy[2 * i] = st->pts.xy[2 * a[i]];
		xy[2 * i + 1] = st->pts.xy[2 * a[i] + 1];
		label[i] = st->label[a[i]];
		if (z != NULL)
			z[i] = st->pts.z[a[i]];
	}
	memcpy(st->pts.xy, xy, n * 2 * sizeof(double));
	memcpy(st->label, label, n * sizeof(int64));
	if (z != NULL)
		memcpy(st->pts.z, z, n * sizeof(double));
	pfree(xy);
	pfree(label);
	if (z != NULL)
		pfree(z);
	pfree(a);
	pfree(b);
	st->unordered = false;
}

PG_FUNCTION_INFO_V1(_tdc_tile_transfn);

/*
 * _tdc_tile_transfn(state, g geometry, label int8, self int8,
 *					  known float8[4], hull float8[], extra float8[],
 *					  seq int8, vi int8)
 * Appends the vertices of g, each owned by tile "label", at source position
 * (seq, vi).  self, known, hull and the extra known boxes (4 values each,
 * every point inside them is passed too) are the tile's and are taken from
 * the first row.  The rows may come in any order: the final function puts
 * them back in source order (sort_by_source).
 */
Datum
_tdc_tile_transfn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt;
	TileState  *st = PG_ARGISNULL(0) ? NULL : (TileState *) PG_GETARG_POINTER(0);
	int64		label;
	int64		seq;
	int64		vi;
	uint64		before;

	tdc_signal_guard();
	if (!AggCheckCallContext(fcinfo, &aggcxt))
		elog(ERROR, "_tdc_tile_transfn called in non-aggregate context");
	if (PG_ARGISNULL(1))
		PG_RETURN_POINTER(st);
	if (PG_ARGISNULL(2) || PG_ARGISNULL(3) || PG_ARGISNULL(4) || PG_ARGISNULL(5) ||
		PG_ARGISNULL(6) || PG_ARGISNULL(7) || PG_ARGISNULL(8))
		ereport(ERROR,
				(errcode(ERRCODE_NULL_VALUE_NOT_ALLOWED),
				 errmsg("%s: label, tile, known box, hull and source position must not be NULL",
						TILED_FNAME)));
	label = PG_GETARG_INT64(2);
	seq = PG_GETARG_INT64(7);
	vi = PG_GETARG_INT64(8);

	if (st == NULL)
	{
		MemoryContext old = MemoryContextSwitchTo(aggcxt);
		double	   *known;
		int			nk;

		st = palloc0(sizeof(TileState));
		tdc_pointbuf_init(&st->pts, aggcxt);
		st->self = PG_GETARG_INT64(3);
		read_box_array(PG_GETARG_ARRAYTYPE_P(4), &known, &nk, 4, "the known box");
		if (nk != 4 || !(known[0] <= known[2] && known[1] <= known[3]))
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: the known box must be {xmin, ymin, xmax, ymax}", TILED_FNAME)));
		memcpy(st->known, known, sizeof(st->known));
		read_box_array(PG_GETARG_ARRAYTYPE_P(5), &st->hull, &st->nhull, 2, "the hull");
		st->nhull /= 2;
		read_box_array(PG_GETARG_ARRAYTYPE_P(6), &st->extra, &st->nextra, 0, "the extra boxes");
		if (st->nextra % 4 != 0)
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: the extra boxes must be 4 values each", TILED_FNAME)));
		st->nextra /= 4;
		MemoryContextSwitchTo(old);
	}

	before = st->pts.n;
	(void) tdc_read_geometry(&st->pts, PG_GETARG_DATUM(1), TILED_FNAME);

	if (st->pts.n > st->label_cap)
	{
		uint64		cap = Max(st->pts.cap, Max(st->label_cap * 2, 1024));

		tdc_pointbuf_side_grow(&st->pts, st->label_cap * 3 * sizeof(int64),
							   cap * 3 * sizeof(int64),
							   "their tiles and source positions", TILED_FNAME);
		if (st->label == NULL)
		{
			st->label = MemoryContextAllocHuge(aggcxt, cap * sizeof(int64));
			st->key = MemoryContextAllocHuge(aggcxt, cap * 2 * sizeof(int64));
		}
		else
		{
			st->label = repalloc_huge(st->label, cap * sizeof(int64));
			st->key = repalloc_huge(st->key, cap * 2 * sizeof(int64));
		}
		st->label_cap = cap;
	}
	for (uint64 i = before; i < st->pts.n; i++)
	{
		st->label[i] = label;
		st->key[2 * i] = seq;
		st->key[2 * i + 1] = vi;
		if (i > 0 && key_cmp(st->key, i - 1, i) > 0)
			st->unordered = true;
	}
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(_tdc_tile_finalfn);

/*
 * The tile's final triangles, or the box it needs, as a TileOut bytea.
 * The triangulation runs interruptibly (tdc_run), within
 * tdc_delaunay.max_memory: a tile whose halo is too big is an ERROR.
 */
Datum
_tdc_tile_finalfn(PG_FUNCTION_ARGS)
{
	TileState  *st = PG_ARGISNULL(0) ? NULL : (TileState *) PG_GETARG_POINTER(0);
	tdc_tile_spec spec;
	tdc_tile_result res;
	TdcRun	   *run;
	TileOut    *out;
	char		err[256];
	int			rc;
	int			dim;
	uint64		size;
	uint64		result_bytes;

	tdc_signal_guard();
	if (!AggCheckCallContext(fcinfo, NULL))
		elog(ERROR, "_tdc_tile_finalfn called in non-aggregate context");
	if (st == NULL || st->pts.n == 0)
		PG_RETURN_NULL();
	dim = st->pts.hasz ? 3 : 2;

	/*
	 * The result is at most 2n triangles: count it against the limit.  The
	 * sort's own arrays (at most 48 bytes a vertex, freed before the run)
	 * weigh less than the engine's, so the run's check covers them, as long
	 * as it comes first.
	 */
	result_bytes = (uint64) st->pts.n * 2 * 3 * dim * sizeof(double);
	tdc_check_run_memory(&st->pts, 0.0, result_bytes, TILED_FNAME);
	sort_by_source(st);

	memset(&spec, 0, sizeof(spec));
	spec.tile = st->label;
	spec.self = st->self;
	memcpy(spec.known, st->known, sizeof(spec.known));
	spec.hull = st->hull;
	spec.nhull = st->nhull;
	spec.extra = st->extra;
	spec.nextra = st->nextra;

	run = tdc_run(&st->pts, 0.0, result_bytes, TILED_FNAME);
	memset(&res, 0, sizeof(res));
	err[0] = '\0';
	rc = tdc_tile_finish(run->job, &spec, &res, err, sizeof(err));
	if (rc != TDC_OK)
	{
		tdc_tile_result_free(&res);
		tdc_run_free(run);
		ereport(ERROR,
				(errcode(ERRCODE_INTERNAL_ERROR),
				 errmsg("%s: tile " INT64_FORMAT ": %s", TILED_FNAME, st->self, err)));
	}

	size = sizeof(TileOut) + (res.final ? (uint64) res.ntri * 3 * dim * sizeof(double) : 0);
	if (size > MaxAllocSize)
	{
		uint64		ntri = res.ntri;

		tdc_tile_result_free(&res);
		tdc_run_free(run);
		ereport(ERROR,
				(errcode(ERRCODE_PROGRAM_LIMIT_EXCEEDED),
				 errmsg("%s: tile " INT64_FORMAT " has %llu triangles, more than one value can hold",
						TILED_FNAME, st->self, (unsigned long long) ntri),
				 errhint("Use smaller tiles (tile_size, or a finer tile column).")));
	}
	out = palloc(size);
	SET_VARSIZE(out, size);
	out->final = res.final;
	out->srid = st->pts.srid;
	out->hasz = st->pts.hasz;
	memcpy(out->need, res.final ? st->known : res.need, sizeof(out->need));
	out->ntri = res.final ? res.ntri : 0;
	if (res.final)
	{
		double	   *p = (double *) (out + 1);

		for (uint64 t = 0; t < res.ntri; t++)
			for (int j = 0; j < 3; j++)
			{
				size_t		i = res.tri[3 * t + j];

				*p++ = st->pts.xy[2 * i];
				*p++ = st->pts.xy[2 * i + 1];
				if (dim == 3)
					*p++ = st->pts.z[i];
			}
	}
	tdc_tile_result_free(&res);
	tdc_run_free(run);
	PG_RETURN_BYTEA_P(out);
}

/*
 * A POLYGON value of one ring of 5 vertices (dim doubles each, Z 0): the
 * box b {xmin, ymin, xmax, ymax} a tile that is not final needs, as
 * (xmin ymin, xmax ymin, xmax ymax, xmin ymax, xmin ymin).
 */
static Datum
make_box_polygon(const double b[4], int dim, int32 srid)
{
	const double c[5][2] = {{b[0], b[1]}, {b[2], b[1]}, {b[2], b[3]}, {b[0], b[3]}, {b[0], b[1]}};
	Size		size = VARHDRSZ + G_HEADER + 16 + (Size) 5 * dim * sizeof(double);
	char	   *out = palloc0(size);
	unsigned char *h = (unsigned char *) VARDATA(out);
	uint32		s = (uint32) srid & 0x1fffff;
	uint32		u[4] = {G_POLYGON, 1, 5, 0};
	double	   *p = (double *) (VARDATA(out) + G_HEADER + 16);

	SET_VARSIZE(out, size);
	h[0] = (unsigned char) (s >> 16);
	h[1] = (unsigned char) (s >> 8);
	h[2] = (unsigned char) s;
	h[3] = GF_VERSION | (dim == 3 ? GF_Z : 0);
	memcpy(VARDATA(out) + G_HEADER, u, sizeof(u));
	for (int i = 0; i < 5; i++)
	{
		*p++ = c[i][0];
		*p++ = c[i][1];
		if (dim == 3)
			*p++ = 0;
	}
	return PointerGetDatum(out);
}

PG_FUNCTION_INFO_V1(_tdc_tile_triangles);

/*
 * _tdc_tile_triangles(r bytea) RETURNS TABLE(k bigint, geom geometry)
 * A final tile's triangles numbered k = 1.., or for a tile that is not
 * final one row k = 0 holding the box it needs as a POLYGON
 * (xmin ymin, xmax ymin, xmax ymax, xmin ymax, xmin ymin).
 *
 * One row per call: called in a select list (ProjectSet) the rows go
 * straight to an INSERT, where a materialized set of a tile's million
 * triangles would be written to a tuplestore, spilled to disk past
 * work_mem, and read back.  (In FROM, as the rounds on Citus call it, the
 * executor collects the rows itself.)
 */
Datum
_tdc_tile_triangles(PG_FUNCTION_ARGS)
{
	FuncCallContext *fctx;
	const bytea *in;
	TileOut		h;
	int			dim;
	Datum		values[2];
	bool		nulls[2] = {false, false};
	HeapTuple	tuple;

	tdc_signal_guard();
	if (SRF_IS_FIRSTCALL())
	{
		MemoryContext old;
		TupleDesc	desc;

		fctx = SRF_FIRSTCALL_INIT();
		old = MemoryContextSwitchTo(fctx->multi_call_memory_ctx);
		/* no copy of a plain value: the argument stays valid across calls */
		in = (const bytea *) PG_DETOAST_DATUM(PG_GETARG_DATUM(0));
		if (VARSIZE(in) < sizeof(TileOut))
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: not a tile result", TILED_FNAME)));
		memcpy(&h, in, sizeof(h));
		dim = h.hasz ? 3 : 2;
		if ((h.final != 0 && h.final != 1) || (h.final == 0 && h.ntri != 0) ||
			VARSIZE(in) != sizeof(TileOut) + h.ntri * 3 * dim * sizeof(double))
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: corrupt tile result", TILED_FNAME)));
		if (get_call_result_type(fcinfo, NULL, &desc) != TYPEFUNC_COMPOSITE)
			elog(ERROR, "%s: return type must be a row type", TILED_FNAME);
		fctx->tuple_desc = BlessTupleDesc(desc);
		fctx->user_fctx = (void *) in;
		fctx->max_calls = h.final ? h.ntri : 1;
		MemoryContextSwitchTo(old);
	}
	fctx = SRF_PERCALL_SETUP();
	if (fctx->call_cntr >= fctx->max_calls)
		SRF_RETURN_DONE(fctx);
	CHECK_FOR_INTERRUPTS();

	in = (const bytea *) fctx->user_fctx;
	memcpy(&h, in, sizeof(h));
	dim = h.hasz ? 3 : 2;
	if (!h.final)
	{
		values[0] = Int64GetDatum(0);
		values[1] = make_box_polygon(h.need, dim, h.srid);
	}
	else
	{
		const double *tri = (const double *) ((const char *) in + sizeof(TileOut)) +
			fctx->call_cntr * 3 * dim;
		struct varlena *g = palloc(tdc_gser_triangle_size(dim == 3));

		tdc_gser_write_triangle_coords(g, tri, dim, h.srid);
		values[0] = Int64GetDatum((int64) fctx->call_cntr + 1);
		values[1] = PointerGetDatum(g);
	}
	tuple = heap_form_tuple(fctx->tuple_desc, values, nulls);
	SRF_RETURN_NEXT(fctx, HeapTupleGetDatum(tuple));
}

PG_FUNCTION_INFO_V1(_tdc_first_box);

/*
 * _tdc_first_box(x float8, y float8, boxes float8[], i int4) RETURNS bool
 * Whether box i (from 0) of boxes {xmin,ymin,xmax,ymax,...} is the first
 * that holds the point (closed boxes).  The procedure takes a halo point
 * from the first of a tile's known boxes that holds it, so that a point in
 * several of them is passed once; a NOT EXISTS over generate_series said
 * the same at the cost of a subplan per point.
 */
Datum
_tdc_first_box(PG_FUNCTION_ARGS)
{
	double		x = PG_GETARG_FLOAT8(0);
	double		y = PG_GETARG_FLOAT8(1);
	ArrayType  *a = PG_GETARG_ARRAYTYPE_P(2);
	int32		i = PG_GETARG_INT32(3);
	int			n;
	const double *b;

	if (ARR_NDIM(a) > 1 || ARR_ELEMTYPE(a) != FLOAT8OID || ARR_HASNULL(a))
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: the boxes must be a one-dimensional float8 array without NULLs",
						TILED_FNAME)));
	n = ARR_NDIM(a) == 0 ? 0 : ARR_DIMS(a)[0];
	if (n % 4 != 0 || i < 0 || i >= n / 4)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: box %d of %d boxes", TILED_FNAME, i, n / 4)));
	b = (const double *) ARR_DATA_PTR(a);
	if (!(b[4 * i] <= x && x <= b[4 * i + 2] && b[4 * i + 1] <= y && y <= b[4 * i + 3]))
		PG_RETURN_BOOL(false);
	for (int j = 0; j < i; j++)
		if (b[4 * j] <= x && x <= b[4 * j + 2] && b[4 * j + 1] <= y && y <= b[4 * j + 3])
			PG_RETURN_BOOL(false);
	PG_RETURN_BOOL(true);
}

/*
 * _tdc_hull(geometry) and _tdc_hull(float8[] of x,y pairs): the exact convex
 * hull of all vertices as {x,y,...} counter-clockwise, the polygon C of the
 * tiles (tdc_tile_spec.hull).  The hull of a union is the hull of the parts'
 * hulls, so the state is a buffer that is replaced by its hull whenever it
 * fills: bounded memory for any table, and per-tile hulls (computed on the
 * workers on Citus) can be combined by the float8[] form.
 */
#define HULL_BUFFER		65536

typedef struct HullState
{
	double	   *xy;				/* HULL_BUFFER + slack pairs */
	uint64		n;
	uint64		cap;
} HullState;

static void
hull_reduce(HullState *st)
{
	double	   *hull = NULL;
	size_t		nh = 0;

	if (tdc_convex_hull(st->xy, (size_t) st->n, &hull, &nh) != TDC_OK)
		ereport(ERROR,
				(errcode(ERRCODE_OUT_OF_MEMORY),
				 errmsg("%s: out of memory computing the convex hull", TILED_FNAME)));
	if (nh > 0)
		memcpy(st->xy, hull, nh * 2 * sizeof(double));
	st->n = nh;
	free(hull);
}

static void
hull_add(HullState *st, const double *xy, uint64 n, MemoryContext cxt)
{
	for (uint64 i = 0; i < n; i++)
	{
		if (!isfinite(xy[2 * i]) || !isfinite(xy[2 * i + 1]))
			ereport(ERROR,
					(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
					 errmsg("%s: non-finite coordinate", TILED_FNAME)));
		if (st->n == st->cap)
		{
			hull_reduce(st);
			if (st->n * 2 > st->cap)
			{
				st->cap *= 2;
				st->xy = repalloc_huge(st->xy, st->cap * 2 * sizeof(double));
			}
		}
		st->xy[2 * st->n] = xy[2 * i];
		st->xy[2 * st->n + 1] = xy[2 * i + 1];
		st->n++;
	}
}

PG_FUNCTION_INFO_V1(_tdc_hull_transfn);

Datum
_tdc_hull_transfn(PG_FUNCTION_ARGS)
{
	MemoryContext aggcxt;
	HullState  *st = PG_ARGISNULL(0) ? NULL : (HullState *) PG_GETARG_POINTER(0);
	Oid			argtype = get_fn_expr_argtype(fcinfo->flinfo, 1);

	tdc_signal_guard();
	if (!AggCheckCallContext(fcinfo, &aggcxt))
		elog(ERROR, "_tdc_hull_transfn called in non-aggregate context");
	if (PG_ARGISNULL(1))
		PG_RETURN_POINTER(st);
	if (st == NULL)
	{
		st = MemoryContextAllocZero(aggcxt, sizeof(HullState));
		st->cap = HULL_BUFFER;
		st->xy = MemoryContextAllocHuge(aggcxt, st->cap * 2 * sizeof(double));
	}
	if (argtype == FLOAT8ARRAYOID)
	{
		double	   *xy;
		int			n;

		read_box_array(PG_GETARG_ARRAYTYPE_P(1), &xy, &n, 0, "a hull");
		hull_add(st, xy, n / 2, aggcxt);
		pfree(xy);
	}
	else
	{
		TdcPointBuf buf;

		tdc_pointbuf_init(&buf, CurrentMemoryContext);
		(void) tdc_read_geometry(&buf, PG_GETARG_DATUM(1), TILED_FNAME);
		if (buf.n > 0)
			hull_add(st, buf.xy, buf.n, aggcxt);
	}
	PG_RETURN_POINTER(st);
}

PG_FUNCTION_INFO_V1(_tdc_hull_finalfn);

Datum
_tdc_hull_finalfn(PG_FUNCTION_ARGS)
{
	HullState  *st = PG_ARGISNULL(0) ? NULL : (HullState *) PG_GETARG_POINTER(0);
	Datum	   *d;

	tdc_signal_guard();
	if (st == NULL || st->n == 0)
		PG_RETURN_NULL();
	hull_reduce(st);
	d = palloc(sizeof(Datum) * st->n * 2);
	for (uint64 i = 0; i < st->n * 2; i++)
		d[i] = Float8GetDatum(st->xy[i]);
	PG_RETURN_ARRAYTYPE_P(construct_array(d, (int) st->n * 2, FLOAT8OID, 8,
										  FLOAT8PASSBYVAL, TYPALIGN_DOUBLE));
}

PG_FUNCTION_INFO_V1(_tdc_curve_to_line);

/*
 * _tdc_curve_to_line(geometry) RETURNS geometry
 *		The geometry as the Delaunay functions read it: stroked when it has
 *		arcs, else itself.  tdc_delaunay_tiled stages the vertices of its
 *		source with ST_DumpPoints in SQL, and runs its curve rows through
 *		this first, so that its tiles see what ST_TDCDelaunayDump sees.  The
 *		value is read once to decide (its arcs, its empty arcs), as the
 *		Delaunay functions decide.
 */
Datum
_tdc_curve_to_line(PG_FUNCTION_ARGS)
{
	const char *fname = "tdc_delaunay_tiled";
	Datum		d = PG_GETARG_DATUM(0);
	MemoryContext cxt;
	TdcPointBuf buf;
	bool		stroked;

	tdc_signal_guard();
	cxt = AllocSetContextCreate(CurrentMemoryContext, "tdc curve check",
								ALLOCSET_SMALL_SIZES);
	tdc_pointbuf_init(&buf, cxt);
	buf.curves = TDC_CURVES_STROKE;
	stroked = tdc_read_geometry(&buf, d, fname);
	MemoryContextDelete(cxt);
	if (!stroked)
		PG_RETURN_DATUM(d);
	PG_RETURN_POINTER(tdc_curve_to_line(d, fname));
}
