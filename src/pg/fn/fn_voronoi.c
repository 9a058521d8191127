/*
 * fn_voronoi.c
 *		ST_TDCVoronoiPolygons and ST_TDCVoronoiLines: the Voronoi diagram of
 *		a geometry's vertices, built by the core (voronoi.c) from the exact
 *		triangulation, as drop-ins for PostGIS's ST_VoronoiPolygons and
 *		ST_VoronoiLines.
 *
 * Behaviour matched with PostGIS 3.3 (GEOS 3.11), checked on the installed
 * versions:
 *	- g1 NULL gives NULL; extend_to NULL means none; tolerance NULL or
 *	  negative is an error (so the function is not STRICT);
 *	- fewer than 2 distinct sites give GEOMETRYCOLLECTION EMPTY with g1's
 *	  SRID, for both functions;
 *	- the clip envelope is GEOS's VoronoiDiagramBuilder rule: the sites'
 *	  bounding box grown on every side by the larger of its width and
 *	  height, then grown to include extend_to's bounding box, rounded
 *	  outward to floats as PostGIS reads it; an EMPTY extend_to is an error;
 *	- the result has g1's SRID (extend_to's SRID is ignored, as in PostGIS),
 *	  and is 2D whatever g1's dimensions;
 *	- ST_TDCVoronoiLines gives a LINESTRING when the diagram has one edge,
 *	  else a MULTILINESTRING of every Voronoi edge inside the envelope, each
 *	  once, none along the envelope's border.
 * Where PostGIS's order is arbitrary, the cells come in the input order of
 * the first vertex of each site.  Rings are counter-clockwise (GEOS's are
 * clockwise).  Differences: "tolerance" is the exact merge rule of
 * ST_TDCDelaunayTriangles (GEOS only snaps during insertion, and keeps
 * points closer than the tolerance apart); NaN and infinite tolerances are
 * errors.  A curve's sites are its stored vertices, its control points, as
 * GEOS gets them from PostGIS (the Delaunay functions stroke curves instead,
 * as ST_DelaunayTriangles does: see curves.c).
 *
 * The diagram is built on the core's threads while the backend waits
 * interruptibly, as a triangulation is: a cancel stops the workers, and a
 * reset callback on the input's memory context frees the diagram (before
 * the job it reads) if an error leaves early.  The polygons are written the
 * same way: the core sizes the cells, this thread allocates the value, and
 * the core's threads write the cells into it in input order through
 * tdc_polygon_cell_writer, which only copies bytes (no PostgreSQL call off
 * this thread); so the bytes are the same whatever the thread count.  The
 * lines, each edge once, are written here.
 */
#include "postgres.h"

#include <float.h>
#include <math.h>

#include "fmgr.h"
#include "miscadmin.h"
#include "utils/memutils.h"

#include "formats/gser_format.h"
#include "fn_voronoi.h"

struct VorRun
{
	tdc_voronoi *v;				/* NULL once freed */
};

static void
vor_reset_callback(void *arg)
{
	VorRun	   *run = (VorRun *) arg;

	if (run->v != NULL)
	{
		tdc_voronoi_free(run->v);
		run->v = NULL;
	}
}

TDC_WORK_OPS(vor_ops, tdc_voronoi, tdc_voronoi, "Voronoi diagram");

/*
 * The bounding box of extend_to's vertices into ext[4], as PostGIS reads
 * it: rounded outward to floats, the form in which every geometry's box is
 * stored, and in which PostGIS hands even a point's to GEOS.  The exact
 * extent would move the cells along that side by up to a float's rounding
 * (a relative 6e-8) from PostGIS's.  A bound beyond the float range stays
 * exact: rounded, it would be infinite.  An EMPTY geometry is an error, as
 * in PostGIS.
 */
void
tdc_voronoi_extend_to_box(Datum g, double ext[4], const char *fname)
{
	TdcPointBuf b;
	MemoryContext cxt = AllocSetContextCreate(CurrentMemoryContext, "tdc extend_to",
											  ALLOCSET_SMALL_SIZES);

	tdc_pointbuf_init(&b, cxt);
	(void) tdc_read_geometry(&b, g, fname);
	if (b.n == 0)
		ereport(ERROR,
				(errcode(ERRCODE_INVALID_PARAMETER_VALUE),
				 errmsg("%s: could not determine the envelope of extend_to: it is empty",
						fname)));
	ext[0] = ext[2] = b.xy[0];
	ext[1] = ext[3] = b.xy[1];
	for (uint64 i = 1; i < b.n; i++)
	{
		ext[0] = fmin(ext[0], b.xy[2 * i]);
		ext[2] = fmax(ext[2], b.xy[2 * i]);
		ext[1] = fmin(ext[1], b.xy[2 * i + 1]);
		ext[3] = fmax(ext[3], b.xy[2 * i + 1]);
	}
	for (int k = 0; k < 4; k++)
	{
		double		r = k < 2 ? tdc_float_down(ext[k]) : tdc_float_up(ext[k]);

		if (isfinite(r) && fabs(r) <= FLT_MAX)
			ext[k] = r;
	}
	MemoryContextDelete(cxt);
}

/*
 * Triangulate buf and build its diagram clipped to GEOS's envelope (grown
 * to ext when given).  Returns NULL, with nothing running, when there are
 * fewer than 2 sites.  *runp owns the job, the returned VorRun the diagram;
 * the caller frees both with tdc_voronoi_result_free.  With a writer, the
 * cells are only sized, for tdc_voronoi_write_polygons.
 */
VorRun *
tdc_voronoi_run(const TdcPointBuf *buf, double tolerance, const double *ext,
				const tdc_cell_writer *writer, TdcRun **runp, const char *fname)
{
	TdcRun	   *run;
	VorRun	   *vrun;
	MemoryContextCallback *cb;
	double		env[4];
	char		err[256];
	int			rc;

	*runp = NULL;
	if (buf->n < 2)
		return NULL;
	run = tdc_run(buf, tolerance, tdc_voronoi_memory((size_t) buf->n, 0), fname);
	*runp = run;
	if (tdc_num_sites(run->job) < 2)
		return NULL;
	tdc_voronoi_default_env(run->job, env);
	if (ext)
	{
		env[0] = fmin(env[0], ext[0]);
		env[1] = fmin(env[1], ext[1]);
		env[2] = fmax(env[2], ext[2]);
		env[3] = fmax(env[3], ext[3]);
	}
	if (!isfinite(env[0]) || !isfinite(env[1]) || !isfinite(env[2]) || !isfinite(env[3]))
		ereport(ERROR,
				(errcode(ERRCODE_NUMERIC_VALUE_OUT_OF_RANGE),
				 errmsg("%s: the clip envelope overflows double precision", fname)));

	vrun = MemoryContextAllocZero(buf->cxt, sizeof(VorRun));
	cb = MemoryContextAllocZero(buf->cxt, sizeof(MemoryContextCallback));
	cb->func = vor_reset_callback;
	cb->arg = vrun;
	/* registered after the job's: runs before it, the diagram reads the job */
	MemoryContextRegisterResetCallback(buf->cxt, cb);
	rc = writer ? tdc_voronoi_start_emit(run->job, env, 0, writer, &vrun->v, err, sizeof(err)) :
		tdc_voronoi_start(run->job, env, 0, &vrun->v, err, sizeof(err));
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	tdc_finish_work((void **) &vrun->v, &vor_ops, fname);
	return vrun;
}

const tdc_voronoi *
tdc_voronoi_of(const VorRun *vrun)
{
	return vrun->v;
}

void
tdc_voronoi_result_free(VorRun *vrun, TdcRun *run)
{
	if (vrun && vrun->v)
	{
		tdc_voronoi_free(vrun->v);
		vrun->v = NULL;
	}
	if (run)
		tdc_run_free(run);
}

/* ----------------------------------------------------------------
 *		writing
 * ----------------------------------------------------------------
 */
static char *
put_u32(char *p, uint32 v)
{
	memcpy(p, &v, 4);
	return p + 4;
}

static char *
write_header(Size size, int32 srid, char **body)
{
	char	   *out = palloc(size);
	unsigned char *h = (unsigned char *) VARDATA(out);
	uint32		s = (uint32) srid & 0x1fffff;

	tdc_advise_result(out, size);
	SET_VARSIZE(out, size);
	h[0] = (unsigned char) (s >> 16);
	h[1] = (unsigned char) (s >> 8);
	h[2] = (unsigned char) s;
	h[3] = GF_VERSION;
	*body = VARDATA(out) + G_HEADER;
	return out;
}

/*
 * Calls fn(arg, site) for every site once, in the input order of its first
 * vertex.
 */
static void
for_sites_in_input_order(const tdc_job *job, void (*fn) (void *, uint32), void *arg)
{
	size_t		n = tdc_num_input(job);
	uint32		lim = tdc_site_id_limit(job);
	uint64	   *seen = palloc0(((Size) lim / 64 + 1) * sizeof(uint64));

	for (size_t i = 0; i < n; i++)
	{
		uint32		s = tdc_input_site(job, i);

		if (s == UINT32_MAX)
			ereport(ERROR, (errcode(ERRCODE_OUT_OF_MEMORY),
							errmsg("out of memory mapping the input to its sites")));
		if (seen[s / 64] & ((uint64) 1 << (s % 64)))
			continue;
		seen[s / 64] |= (uint64) 1 << (s % 64);
		if ((i & 65535) == 0)
			CHECK_FOR_INTERRUPTS();
		fn(arg, s);
	}
	pfree(seen);
}

/* ST_TDCVoronoiLines's writer: sized in a first pass, written in a second */
typedef struct PolyWriter
{
	const tdc_voronoi *v;
	const double *env;
	uint64		size;			/* pass 1: bytes of the members */
	uint32		count;			/* members */
	char	   *p;				/* pass 2: where the next member goes */
	bool		writing;
} PolyWriter;

/*
 * The cell writer of a polygon collection (tdc_cell_writer): runs on the
 * core's worker threads, so it only copies bytes.  A cell of m vertices is
 * a POLYGON of one ring closed by repeating its first vertex.
 */
static size_t
polygon_cell_size(void *arg, size_t m)
{
	return 16 + 16 * (m + 1);
}

static void
polygon_cell_write(void *arg, char *dst, const double *xy, size_t m)
{
	uint32		h[4] = {G_POLYGON, 1, (uint32) (m + 1), 0};	/* 0 pads the ring counts */

	memcpy(dst, h, sizeof(h));
	memcpy(dst + 16, xy, 16 * m);
	memcpy(dst + 16 + 16 * m, xy, 16);
}

const tdc_cell_writer tdc_polygon_cell_writer = {polygon_cell_size, polygon_cell_write, NULL};

/*
 * The diagram of a run started with tdc_polygon_cell_writer as one
 * GEOMETRYCOLLECTION of POLYGONs: the value is allocated here, at the size
 * the core found, and the core's threads write the cells into it while
 * this thread waits as for the diagram.
 */
struct varlena *
tdc_voronoi_write_polygons(VorRun *vrun, int32 srid, uint64 have_bytes,
						   const char *fname)
{
	size_t		count;
	uint64		bytes = tdc_voronoi_emit_size(vrun->v, &count);
	uint64		size = VARHDRSZ + G_HEADER + 8 + bytes;
	uint64		limit = tdc_max_memory_bytes();
	char	   *out,
			   *p;
	char		err[256];
	int			rc;

	tdc_gser_check_result_size(size, fname);
	if (limit > 0 && have_bytes + size > limit)
		tdc_report_memory_limit(fname, "writing the Voronoi diagram", have_bytes + size, 0);
	out = write_header((Size) size, srid, &p);
	/* the workers fault the pages in */
	p = put_u32(p, G_COLLECTION);
	p = put_u32(p, (uint32) count);
	rc = tdc_voronoi_emit(vrun->v, p, err, sizeof(err));
	if (rc != TDC_OK)
		tdc_report_status(rc, err, fname);
	tdc_finish_work((void **) &vrun->v, &vor_ops, fname);
	return (struct varlena *) out;
}

static bool
on_env_side(const double *e, const double *p, const double *q)
{
	return (p[0] == e[0] && q[0] == e[0]) || (p[0] == e[2] && q[0] == e[2]) ||
		(p[1] == e[1] && q[1] == e[1]) || (p[1] == e[3] && q[1] == e[3]);
}

/*
 * A cell's Voronoi edges: each appears in the two cells beside it with its
 * end points swapped and bit-identical, so taking it where it runs from
 * the lexicographically smaller end point takes it once.
 */
static void
line_members(void *arg, uint32 s)
{
	PolyWriter *w = arg;
	const double *c;
	size_t		m = tdc_voronoi_cell(w->v, s, &c);

	for (size_t i = 0; i < m; i++)
	{
		const double *p = c + 2 * i,
				   *q = c + 2 * ((i + 1) % m);

		if (!(p[0] < q[0] || (p[0] == q[0] && p[1] < q[1])) || on_env_side(w->env, p, q))
			continue;
		if (!w->writing)
		{
			w->size += 8 + 32;
			w->count++;
			continue;
		}
		w->p = put_u32(w->p, G_LINE);
		w->p = put_u32(w->p, 2);
		memcpy(w->p, p, 16);
		memcpy(w->p + 16, q, 16);
		w->p += 32;
	}
}

/*
 * The diagram's edges as one value: a MULTILINESTRING, or a LINESTRING when
 * there is one edge.  (The polygons are written by the core's threads:
 * tdc_voronoi_write_polygons.)
 */
struct varlena *
tdc_voronoi_write_lines(const tdc_job *job, const tdc_voronoi *v, int32 srid,
						uint64 have_bytes, const char *fname)
{
	PolyWriter	w;
	uint64		size;
	char	   *out,
			   *p;
	double		env[4];
	uint64		limit = tdc_max_memory_bytes();

	memset(&w, 0, sizeof(w));
	w.v = v;
	tdc_voronoi_env(v, env);
	w.env = env;
	for_sites_in_input_order(job, line_members, &w);
	if (w.count == 1)
		size = VARHDRSZ + G_HEADER + w.size;
	else
		size = VARHDRSZ + G_HEADER + 8 + w.size;
	tdc_gser_check_result_size(size, fname);
	if (limit > 0 && have_bytes + size > limit)
		tdc_report_memory_limit(fname, "writing the Voronoi diagram", have_bytes + size, 0);
	out = write_header((Size) size, srid, &p);
	tdc_prefault(out, (size_t) size);
	if (w.count != 1)
	{
		p = put_u32(p, G_MULTILINE);
		p = put_u32(p, w.count);
	}
	w.writing = true;
	w.p = p;
	for_sites_in_input_order(job, line_members, &w);
	Assert(w.p == out + size);
	return (struct varlena *) out;
}

/* One cell as a POLYGON value (closed ring), or NULL for a non-site. */
struct varlena *
tdc_voronoi_cell_value(const tdc_voronoi *v, uint32 site, int32 srid)
{
	const double *c;
	size_t		m = tdc_voronoi_cell(v, site, &c);
	char	   *out,
			   *p;

	if (m == 0)
		return NULL;
	out = write_header(VARHDRSZ + G_HEADER + 16 + 16 * (m + 1), srid, &p);
	p = put_u32(p, G_POLYGON);
	p = put_u32(p, 1);
	p = put_u32(p, (uint32) (m + 1));
	p = put_u32(p, 0);
	memcpy(p, c, m * 2 * sizeof(double));
	memcpy(p + m * 2 * sizeof(double), c, 2 * sizeof(double));
	return (struct varlena *) out;
}

/* ----------------------------------------------------------------
 *		SQL functions
 * ----------------------------------------------------------------
 */
static Datum
voronoi_function(FunctionCallInfo fcinfo, bool lines, const char *fname)
{
	double		tolerance,
				ext[4];
	bool		have_ext = false;
	TdcPointBuf buf;

	if (PG_ARGISNULL(0))
		PG_RETURN_NULL();
	tdc_check_tolerance(PG_NARGS() > 1 && PG_ARGISNULL(1),
						PG_NARGS() > 1 && !PG_ARGISNULL(1) ? PG_GETARG_FLOAT8(1) : 0.0,
						fname);
	tolerance = PG_NARGS() > 1 ? PG_GETARG_FLOAT8(1) : 0.0;
	if (PG_NARGS() > 2 && !PG_ARGISNULL(2))
	{
		tdc_voronoi_extend_to_box(PG_GETARG_DATUM(2), ext, fname);
		have_ext = true;
	}
	tdc_pointbuf_init(&buf, CurrentMemoryContext);
	buf.curves = TDC_CURVES_VERTICES;
	(void) tdc_read_geometry(&buf, PG_GETARG_DATUM(0), fname);
	PG_RETURN_POINTER(tdc_voronoi_to_value(&buf, tolerance, have_ext ? ext : NULL,
										   lines, fname));
}

/*
 * The diagram of buf's vertices as one value (GEOMETRYCOLLECTION EMPTY for
 * fewer than 2 sites), with buf's SRID.
 */
struct varlena *
tdc_voronoi_to_value(const TdcPointBuf *buf, double tolerance, const double *ext,
					 bool lines, const char *fname)
{
	TdcRun	   *run;
	VorRun	   *vrun;
	struct varlena *result;
	uint64		have;

	vrun = tdc_voronoi_run(buf, tolerance, ext, lines ? NULL : &tdc_polygon_cell_writer,
						   &run, fname);
	if (vrun == NULL)
	{
		if (run)
			tdc_run_free(run);
		return tdc_gser_empty(TDC_OUT_POLYGONS, buf->srid);
	}
	have = tdc_pointbuf_bytes(buf) + tdc_estimate_memory((size_t) buf->n, NULL) +
		tdc_voronoi_memory((size_t) buf->n, 0);
	if (lines)
		result = tdc_voronoi_write_lines(run->job, vrun->v, buf->srid, have, fname);
	else
		result = tdc_voronoi_write_polygons(vrun, buf->srid, have, fname);
	CHECK_FOR_INTERRUPTS();
	tdc_voronoi_result_free(vrun, run);
	return result;
}

PG_FUNCTION_INFO_V1(st_tdcvoronoipolygons);
Datum
st_tdcvoronoipolygons(PG_FUNCTION_ARGS)
{
	tdc_signal_guard();
	return voronoi_function(fcinfo, false, "ST_TDCVoronoiPolygons");
}

PG_FUNCTION_INFO_V1(st_tdcvoronoilines);
Datum
st_tdcvoronoilines(PG_FUNCTION_ARGS)
{
	tdc_signal_guard();
	return voronoi_function(fcinfo, true, "ST_TDCVoronoiLines");
}
