/*
 * tin_interp.c
 *		Interpolation on a TIN: the methods and their options (GDAL's
 *		gdal_grid syntax), the value at one point, and the two operations
 *		that compute many: at a list of points, and at the pixel centres of a
 *		grid.
 *
 * The methods.  "linear" is GDAL's: barycentric in the triangle holding the
 * point, and outside the convex hull the nearest site's height when it lies
 * within "radius" (-1: at any distance, the default; 0: never), "nodata"
 * otherwise.  "nearest" is the nearest site's height (ties: the site first
 * in (x, y) order), within radius1 (= radius2; 0, the default: at any
 * distance).  "natural_neighbor" is Sibson's (tin_natural.c), with
 * linear's rule outside the hull.  A point exactly on the hull's boundary
 * is inside: linear along the hull edge for both linear and natural
 * neighbour (the limit of Sibson's value from inside; the cell of such a
 * point is unbounded).  A point at a site has the site's height, exactly,
 * for every method.  GDAL's "radius" of linear compares the distance with
 * <=, and so do we, exactly.
 *
 * Breaklines.  "linear:breaklines=true" is not GDAL's: it asks the host to
 * insert the samples' lines as constraints before building the TIN (the
 * parser only records it), so that the surface follows ridges and streams
 * instead of cutting across them.  Only linear takes it: Sibson's
 * coordinates are made of the Delaunay triangulation's circumcircles,
 * which a constrained triangulation does not keep, and the nearest sample
 * is the same whatever lines lie between; an explicit error there beats an
 * option silently ignored.  On a constrained TIN natural neighbour is
 * refused at the operation's start (tin_spec_ok).
 *
 * max_edge.  Not GDAL's either: LAStools' blast2dem and others leave out
 * the triangles with an edge longer than a limit, so that a lake or a
 * building with no return inside is nodata instead of long facets across
 * it.  Any method takes it, as a mask over the TIN's triangles: where the
 * mask keeps a point the value is the method's, from all the samples; a
 * point strictly inside a dropped triangle has none.  A point on an edge
 * or at a site lies in several closed triangles; the rule a GIS user
 * expects is that a hole is nodata and a measurement is not lost, so a
 * point has a value when some triangle containing it is kept, and a site
 * always has its own height (an isolated sample in a lake keeps it).  An
 * edge is long when its squared length in the (x, y) plane exceeds
 * max_edge^2, exactly (tin_edge_long), so an edge exactly max_edge long is
 * kept and the mask is the same on every machine.  The hull and the radius
 * rule outside it do not change.  The check runs only with the option, on
 * a located point, and costs three to six exact distance comparisons.
 *
 * Many points.  A list of points is cut into chunks, a grid into rows,
 * shared out among the pool's threads; each walks from the triangle of its
 * previous point, which for a grid is the neighbouring pixel's, so the walk
 * is a step or two.  Every value depends on its point and the TIN only
 * (tin_locate.c), so the results are the same for any thread count.  The
 * cancel flag is polled every chunk or row; a coordinate outside the range
 * the predicates are exact on stops the operation with TDC_EINVAL, naming
 * the point.  Each thread keeps one scratch for the natural neighbour
 * cavities (a few kB, more around many cocircular sites), charged against
 * max_memory as it grows.
 */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>

#include "tin_int.h"

#define POINTS_PER_TASK	4096
#define INLINE_WORK		4096	/* points or pixels run on the caller's thread for a small TIN */

/* ----------------------------------------------------------------
 *		the method's text
 * ----------------------------------------------------------------
 */
static bool
parse_number(const char *s, size_t len, double *v)
{
	char		buf[64];
	char	   *end;

	if (len == 0 || len >= sizeof(buf))
		return false;
	memcpy(buf, s, len);
	buf[len] = '\0';
	errno = 0;
	*v = strtod(buf, &end);
	return *end == '\0' && !isnan(*v) && errno != ERANGE;
}

/* GDAL's boolean words (CPLTestBool), but an unknown word is an error. */
static bool
parse_bool(const char *s, size_t len, bool *v)
{
	static const char *const yes[] = {"true", "yes", "on", "1"};
	static const char *const no[] = {"false", "no", "off", "0"};

	for (int i = 0; i < 4; i++)
	{
		if (len == strlen(yes[i]) && strncasecmp(s, yes[i], len) == 0)
		{
			*v = true;
			return true;
		}
		if (len == strlen(no[i]) && strncasecmp(s, no[i], len) == 0)
		{
			*v = false;
			return true;
		}
	}
	return false;
}

int
tdc_interp_parse(const char *text, tdc_interp_spec *spec, char *err, size_t errlen)
{
	const char *p = text,
			   *colon;
	size_t		len;
	double		r1 = 0,
				r2 = 0;
	bool		nearest;

#define FAIL(...) do { if (err && errlen) snprintf(err, errlen, __VA_ARGS__); return TDC_EINVAL; } while (0)
	if (err && errlen)
		err[0] = '\0';
	memset(spec, 0, sizeof(*spec));
	if (text == NULL)
		FAIL("no interpolation method given");
	colon = strchr(p, ':');
	len = colon ? (size_t) (colon - p) : strlen(p);
	if (len == 6 && strncasecmp(p, "linear", 6) == 0)
		spec->method = TDC_INTERP_LINEAR;
	else if (len == 7 && strncasecmp(p, "nearest", 7) == 0)
		spec->method = TDC_INTERP_NEAREST;
	else if (len == 16 && strncasecmp(p, "natural_neighbor", 16) == 0)
		spec->method = TDC_INTERP_NATURAL;
	else
		FAIL("unknown interpolation method \"%.*s\" (linear, nearest or natural_neighbor)",
			 (int) (len < 64 ? len : 64), p);
	nearest = spec->method == TDC_INTERP_NEAREST;
	spec->radius = nearest ? 0 : -1;
	spec->nodata = 0;

	while (colon)
	{
		const char *opt = colon + 1,
				   *eq;
		size_t		olen;
		double		v;

		colon = strchr(opt, ':');
		olen = colon ? (size_t) (colon - opt) : strlen(opt);
		eq = memchr(opt, '=', olen);
		if (eq == NULL)
			FAIL("option \"%.*s\" of %s has no value (name=value)",
				 (int) (olen < 64 ? olen : 64), opt, nearest ? "nearest" :
				 spec->method == TDC_INTERP_LINEAR ? "linear" : "natural_neighbor");
		if ((size_t) (eq - opt) == 10 && strncasecmp(opt, "breaklines", 10) == 0)
		{
			size_t		vlen = olen - (size_t) (eq + 1 - opt);

			if (spec->method != TDC_INTERP_LINEAR)
				FAIL("option \"breaklines\" is an option of linear only: %s",
					 nearest ? "nearest takes the nearest sample, which no line changes" :
					 "natural neighbour coordinates need the unconstrained Delaunay triangulation");
			if (!parse_bool(eq + 1, vlen, &spec->breaklines))
				FAIL("option \"breaklines\": \"%.*s\" is not a boolean (true or false)",
					 (int) (vlen < 64 ? vlen : 64), eq + 1);
			spec->options |= TDC_INTERP_OPT_BREAKLINES;
			continue;
		}
		if (!parse_number(eq + 1, olen - (size_t) (eq + 1 - opt), &v))
			FAIL("option \"%.*s\": \"%.*s\" is not a number",
				 (int) (eq - opt), opt, (int) (olen - (size_t) (eq + 1 - opt) < 64 ?
											   olen - (size_t) (eq + 1 - opt) : 64), eq + 1);
#define IS(name) ((size_t) (eq - opt) == strlen(name) && strncasecmp(opt, name, strlen(name)) == 0)
		if (IS("nodata"))
			spec->nodata = v;
		else if (IS("max_edge"))
		{
			if (!(v > 0))
				FAIL("option \"max_edge\" must be a length > 0, not %g", v);
			spec->max_edge = v;
			spec->options |= TDC_INTERP_OPT_MAX_EDGE;
			continue;
		}
		else if (!nearest && IS("radius"))
			spec->radius = v;
		else if (nearest && IS("radius"))
			r1 = r2 = v;
		else if (nearest && IS("radius1"))
			r1 = v;
		else if (nearest && IS("radius2"))
			r2 = v;
		else if (nearest && IS("angle"))
			;					/* a circle has no orientation */
		else
			FAIL("unknown option \"%.*s\" of %s (%s)", (int) (eq - opt), opt,
				 nearest ? "nearest" : spec->method == TDC_INTERP_LINEAR ? "linear" : "natural_neighbor",
				 nearest ? "radius1, radius2, radius, angle, nodata, max_edge" :
				 spec->method == TDC_INTERP_LINEAR ? "radius, nodata, breaklines, max_edge" :
				 "radius, nodata, max_edge");
		spec->options |= IS("nodata") ? TDC_INTERP_OPT_NODATA : TDC_INTERP_OPT_RADIUS;
#undef IS
	}
	if (nearest)
	{
		if (r1 != r2)
			FAIL("nearest with radius1 %g and radius2 %g: only a circular search (radius1 = radius2) is supported",
				 r1, r2);
		if (r1 < 0)
			FAIL("nearest: radius1 must be >= 0, not %g", r1);
		spec->radius = r1 == 0 ? -1 : r1;
	}
	else if (spec->radius < 0)
		spec->radius = -1;
	/* a radius beyond every distance the coordinates allow: any distance */
	if (spec->radius > 0x1p201)
		spec->radius = -1;
	/* below the exact comparison's range: the smallest in it */
	if (spec->radius > 0 && spec->radius < 0x1p-252)
		spec->radius = 0x1p-252;
	/*
	 * max_edge the same way: beyond 2^201 no edge between coordinates of
	 * magnitude at most TDC_COORD_MAX (< 2^200) is longer, so none; below
	 * 2^-252 every edge is (a nonzero difference of such coordinates is at
	 * least 2^-251), as with the smallest length in the exact range.
	 */
	if (spec->max_edge > 0x1p201)
		spec->max_edge = 0;
	if (spec->max_edge > 0 && spec->max_edge < 0x1p-252)
		spec->max_edge = 0x1p-252;
	return TDC_OK;
#undef FAIL
}

/* ----------------------------------------------------------------
 *		one point
 * ----------------------------------------------------------------
 */
static inline bool
coord_ok(double c)
{
	double		a = fabs(c);

	return c == 0 || (a >= TDC_COORD_MIN && a <= TDC_COORD_MAX);
}

/* Is site s within spec->radius of q (exactly)? */
static bool
within_radius(const tdc_tin *tin, const tdc_interp_spec *spec, const double *q, uint32_t s)
{
	double		r[2] = {spec->radius, 0},
				o[2] = {0, 0};

	if (spec->radius < 0)
		return true;
	if (spec->radius == 0)
		return false;
	return tdc_sqdist_cmp(q, tin_pt(tin, s), r, o) <= 0;
}

/*
 * max_edge.  An edge is long when its squared length exceeds max_edge^2,
 * decided exactly by tdc_sqdist_cmp against the segment (0, 0)-(max_edge,
 * 0), as within_radius decides the radius: the same on every machine, and
 * the same from both triangles beside the edge (the difference of its ends
 * is negated, exactly, from the other side).
 */
bool
tin_edge_long(const tdc_tin *tin, uint32_t a, uint32_t b, double max_edge)
{
	double		l[2] = {max_edge, 0},
				o[2] = {0, 0};

	return tdc_sqdist_cmp(tin_pt(tin, a), tin_pt(tin, b), l, o) > 0;
}

/* Does max_edge keep the triangle left of h (no edge of it longer)? */
bool
tin_face_kept(const tdc_tin *tin, uint32_t h, double max_edge)
{
	for (int k = 0; k < 3; k++, h = tin_lnext(tin, h))
		if (tin_edge_long(tin, tin_org(tin, h), tin_dest(tin, h), max_edge))
			return false;
	return true;
}

/*
 * Does max_edge keep some triangle whose closure holds the point located
 * at lp, strictly inside a triangle or an edge?  An edge: it must not be
 * long itself, and one of the triangles beside it must keep its two other
 * edges; a segment between collinear sites (h NIL) stands alone.
 */
bool
tin_loc_kept(const tdc_tin *tin, const tin_loc *lp, double max_edge)
{
	uint32_t	h = lp->h;

	if (lp->kind == LOC_FACE)
		return tin_face_kept(tin, h, max_edge);
	if (tin_edge_long(tin, lp->a, lp->b, max_edge))
		return false;
	if (h == TDC_NIL)
		return true;
	for (int side = 0; side < 2; side++, h ^= 1u)
	{
		uint32_t	h1 = tin_lnext(tin, h);

		if (!tin_outer(tin, h) &&
			!tin_edge_long(tin, tin_org(tin, h1), tin_dest(tin, h1), max_edge) &&
			!tin_edge_long(tin, tin_dest(tin, h1), tin_dest(tin, tin_lnext(tin, h1)), max_edge))
			return true;
	}
	return false;
}

/*
 * The value at q: 1 and *z, 0 (*z = nodata), or an error.  *hint: where the
 * walk starts, and on return where this one ended; *where (may be NULL):
 * where q lies.
 */
int
tin_value_at(const tdc_tin *tin, const tdc_interp_spec *spec, tin_scratch *sc,
			 const double *q, uint32_t *hint, double *z, tin_loc *where)
{
	tin_loc		local,
			   *lp = where ? where : &local;
	uint32_t	s;
	int			rc;

	*z = spec->nodata;
	lp->kind = LOC_NONE;
	if (!coord_ok(q[0]) || !coord_ok(q[1]))
		return TDC_EINVAL;
	tin_locate(tin, q, *hint, lp);
	if (lp->h != TDC_NIL)
		*hint = lp->h;
	switch (lp->kind)
	{
		case LOC_NONE:
			return 0;
		case LOC_VERTEX:
			*z = tin->sz[lp->a];
			return 1;
		case LOC_OUTSIDE:
			if (spec->method != TDC_INTERP_NEAREST && spec->radius == 0)
				return 0;
			break;
		default:
			/* strictly inside a triangle or an edge: max_edge may drop it */
			if (spec->max_edge > 0 && !tin_loc_kept(tin, lp, spec->max_edge))
				return 0;
			break;
	}
	if (spec->method == TDC_INTERP_NEAREST || lp->kind == LOC_OUTSIDE)
	{
		s = tin_nearest(tin, q, lp);
		if (s == TDC_NIL || !within_radius(tin, spec, q, s))
			return 0;
		*z = tin->sz[s];
		return 1;
	}
	if (lp->kind == LOC_EDGE &&
		(spec->method == TDC_INTERP_LINEAR || lp->h == TDC_NIL || tin_outer(tin, lp->h ^ 1u)))
	{
		*z = tin_lerp_edge(tin, lp->a, lp->b, q);
		return 1;
	}
	if (spec->method == TDC_INTERP_LINEAR)
	{
		*z = tin_linear_face(tin, lp->h, q);
		return 1;
	}
	rc = tin_natural(tin, sc, q, lp, z);
	if (rc != TDC_OK)
	{
		*z = spec->nodata;
		return rc;
	}
	return 1;
}

int
tdc_tin_value(const tdc_tin *tin, const tdc_interp_spec *spec, const double q[2], double *z)
{
	tin_scratch sc;
	uint32_t	hint = TDC_NIL;
	int			rc;

	memset(&sc, 0, sizeof(sc));
	if (!tin->built || !tin_spec_ok(tin, spec, NULL, 0))
		return TDC_EINVAL;
	rc = tin_value_at(tin, spec, &sc, q, &hint, z, NULL);
	tin_scratch_free(&sc);
	return rc;
}

int
tdc_tin_inside(const tdc_tin *tin, const double q[2])
{
	tin_loc		loc;

	if (!tin->built || !coord_ok(q[0]) || !coord_ok(q[1]))
		return 0;
	tin_locate(tin, q, TDC_NIL, &loc);
	return loc.kind == LOC_FACE || loc.kind == LOC_EDGE || loc.kind == LOC_VERTEX;
}

/* ----------------------------------------------------------------
 *		many points: a list, or a grid's pixel centres
 * ----------------------------------------------------------------
 */
typedef struct interp_op
{
	tdc_interp_spec spec;
	const double *xy;			/* points */
	size_t		n;
	tdc_grid_spec grid;			/* or a grid */
	bool		is_grid;
	double	   *z;
	uint8_t    *valid;
	tin_scratch *scratch;		/* one per worker */
	int			nscratch;
} interp_op;

/* A value's error as the operation's: the point named. */
void
tin_point_fail(tdc_tin *tin, int rc, const double *q)
{
	char		msg[200];

	if (rc == TDC_EINVAL)
		snprintf(msg, sizeof(msg),
				 "point (%.17g %.17g): coordinates must be 0 or of magnitude between %g and %g",
				 q[0], q[1], TDC_COORD_MIN, TDC_COORD_MAX);
	else if (rc == TDC_ENOMEM)
		snprintf(msg, sizeof(msg), "out of memory interpolating at (%.17g %.17g)", q[0], q[1]);
	else
		snprintf(msg, sizeof(msg), "natural neighbour cavity at (%.17g %.17g) is not a disk",
				 q[0], q[1]);
	tin_fail(tin, rc == TDC_ENOMEM ? TDC_ENOMEM : TDC_EINVAL, msg);
}

static void
points_task(void *arg, size_t k, int worker)
{
	tdc_tin    *tin = arg;
	interp_op  *op = tin->op_state;
	tin_scratch *sc = &op->scratch[worker];
	size_t		lo = k * POINTS_PER_TASK,
				hi = lo + POINTS_PER_TASK < op->n ? lo + POINTS_PER_TASK : op->n;
	uint32_t	hint = TDC_NIL;

	if (tin_cancelled(tin))
		return;
	for (size_t i = lo; i < hi; i++)
	{
		int			rc = tin_value_at(tin, &op->spec, sc, op->xy + 2 * i, &hint, &op->z[i], NULL);

		if (rc < 0)
		{
			tin_point_fail(tin, rc, op->xy + 2 * i);
			return;
		}
		if (op->valid)
			op->valid[i] = (uint8_t) rc;
		if (!tin_scratch_charge(tin, sc))
			return;
	}
}

static void
grid_task(void *arg, size_t row, int worker)
{
	tdc_tin    *tin = arg;
	interp_op  *op = tin->op_state;
	tin_scratch *sc = &op->scratch[worker];
	const double *gt = op->grid.gt;
	size_t		w = op->grid.width;
	double		fy = (double) row + 0.5;
	uint32_t	hint = TDC_NIL;

	if (tin_cancelled(tin))
		return;
	for (size_t c = 0; c < w; c++)
	{
		double		fx = (double) c + 0.5,
					q[2];
		int			rc;

		q[0] = gt[0] + fx * gt[1] + fy * gt[2];
		q[1] = gt[3] + fx * gt[4] + fy * gt[5];
		rc = tin_value_at(tin, &op->spec, sc, q, &hint, &op->z[row * w + c], NULL);
		if (rc < 0)
		{
			tin_point_fail(tin, rc, q);
			return;
		}
		if (op->valid)
			op->valid[row * w + c] = (uint8_t) rc;
	}
	(void) tin_scratch_charge(tin, sc);
}

static int
interp_run(tdc_tin *tin)
{
	interp_op  *op = tin->op_state;

	if (op->is_grid)
		tdc_pool_for(tin_pool(tin), op->grid.height, grid_task, tin);
	else
		tdc_pool_for(tin_pool(tin), (op->n + POINTS_PER_TASK - 1) / POINTS_PER_TASK,
					 points_task, tin);
	return tin_cancelled(tin) ? TDC_ECANCELED : TDC_OK;
}

static void
interp_free(tdc_tin *tin)
{
	interp_op  *op = tin->op_state;

	if (op == NULL)
		return;
	for (int i = 0; i < op->nscratch; i++)
		tin_scratch_release(tin, &op->scratch[i]);
	free(op->scratch);
	free(op);
	tin->op_state = NULL;
	tin->op_free = NULL;
}

static int
interp_start(tdc_tin *tin, interp_op *op, size_t work, char *err, size_t errlen)
{
	op->nscratch = tin->threads + 1;
	op->scratch = calloc(op->nscratch, sizeof(tin_scratch));
	if (op->scratch == NULL)
	{
		free(op);
		if (err && errlen)
			snprintf(err, errlen, "out of memory");
		return TDC_ENOMEM;
	}
	return tin_op_start(tin, interp_run, op, interp_free,
						tin->nsite_ids <= TDC_INLINE_MAX && work <= INLINE_WORK, err, errlen);
}

/*
 * Can spec run on tin?  Not natural neighbour on a constrained TIN, whose
 * triangles are not the Delaunay ones the coordinates are made of.
 */
bool
tin_spec_ok(const tdc_tin *tin, const tdc_interp_spec *spec, char *err, size_t errlen)
{
	if (spec == NULL || spec->method < TDC_INTERP_LINEAR || spec->method > TDC_INTERP_NATURAL ||
		isnan(spec->radius) || !(spec->max_edge >= 0))
	{
		if (err && errlen)
			snprintf(err, errlen, "bad interpolation method");
		return false;
	}
	if (spec->method == TDC_INTERP_NATURAL && tin->mesh.constrained)
	{
		if (err && errlen)
			snprintf(err, errlen, "natural neighbour interpolation is not defined on a constrained triangulation");
		return false;
	}
	return true;
}

int
tdc_tin_points_start(tdc_tin *tin, const tdc_interp_spec *spec, const double *xy,
					 size_t n, double *z, uint8_t *valid, char *err, size_t errlen)
{
	interp_op  *op;

	if (!tin_spec_ok(tin, spec, err, errlen))
		return TDC_EINVAL;
	if (n > 0 && (xy == NULL || z == NULL))
	{
		if (err && errlen)
			snprintf(err, errlen, "no points or no room for their values");
		return TDC_EINVAL;
	}
	op = calloc(1, sizeof(interp_op));
	if (op == NULL)
	{
		if (err && errlen)
			snprintf(err, errlen, "out of memory");
		return TDC_ENOMEM;
	}
	op->spec = *spec;
	op->xy = xy;
	op->n = n;
	op->z = z;
	op->valid = valid;
	return interp_start(tin, op, n, err, errlen);
}

int
tdc_tin_grid_start(tdc_tin *tin, const tdc_interp_spec *spec, const tdc_grid_spec *grid,
				   double *values, uint8_t *valid, char *err, size_t errlen)
{
	interp_op  *op;

	if (!tin_spec_ok(tin, spec, err, errlen))
		return TDC_EINVAL;
	if (grid == NULL || (grid->width > 0 && grid->height > 0 && values == NULL) ||
		(grid->height > 0 && grid->width > SIZE_MAX / grid->height))
	{
		if (err && errlen)
			snprintf(err, errlen, "bad grid, or no room for its values");
		return TDC_EINVAL;
	}
	for (int i = 0; i < 6; i++)
		if (!isfinite(grid->gt[i]))
		{
			if (err && errlen)
				snprintf(err, errlen, "the grid's geotransform must be finite");
			return TDC_EINVAL;
		}
	op = calloc(1, sizeof(interp_op));
	if (op == NULL)
	{
		if (err && errlen)
			snprintf(err, errlen, "out of memory");
		return TDC_ENOMEM;
	}
	op->spec = *spec;
	op->grid = *grid;
	op->is_grid = true;
	op->z = values;
	op->valid = valid;
	if (grid->width == 0)
		op->grid.height = 0;
	return interp_start(tin, op, grid->width * grid->height, err, errlen);
}
