/*
 * test_tin_maxedge.c
 *		max_edge (issue 39): the triangles with an edge longer than a limit
 *		have no value, no contour and no draped line across them.
 *
 *	- the parser: max_edge with every method, its errors (<= 0, not a
 *	  number, no value), infinity as none; the contours' method check;
 *	- the exact boundary: a 3-4-5 triangle is kept at max_edge 5 and
 *	  dropped at the double below; a triangle whose long edge's squared
 *	  length in double rounds onto max_edge^2 although the exact one is
 *	  larger is dropped (a floating-point shortcut keeps it);
 *	- a lake: a lattice with no sample within 6 of its centre but one
 *	  sample in the middle.  For linear, nearest and natural neighbour the
 *	  values at every site, every edge's midpoint (on the edge, between kept
 *	  and dropped triangles too), random points and a grid's pixel centres
 *	  have a value exactly where an independent oracle says (brute force
 *	  over the triangles, in double arithmetic that is exact on these
 *	  coordinates), and there the value without the option; the sample in
 *	  the lake keeps its height, points beside it have none; outside the
 *	  hull the radius rule holds as before; 1 and 3 threads agree;
 *	- collinear samples: the segment between neighbours decides;
 *	- contours on the lake: per level the length equals an independent sum
 *	  over the kept triangles, lines crossing the lake are cut in two and
 *	  open, their ends on the kept region's boundary, rings beyond the lake
 *	  stay closed; 1 and 3 threads agree; the same on a lattice with many
 *	  lakes, large enough to run on the pool's threads, with a grid;
 *	- draping with linear: pieces through the lake, or along an edge with no
 *	  kept triangle, mark the vertex they start from; a line along an edge
 *	  between kept and dropped triangles, or beside the lake, marks none; a
 *	  vertex in the lake has no value, the sample in it has; collinear
 *	  samples.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"
#include "tin_test.h"

/* a TIN (tin_test.h) and its samples */
typedef struct me_case
{
	tin_case	tc;
	double	   *xy,
			   *z;
	size_t		n;
} me_case;

static bool
me_mk(me_case *c, int threads)
{
	return mk(&c->tc, c->xy, c->z, c->n, threads);
}

/* tdc_tin_value's result, the value in *z */
static int
me_value(const me_case *c, const char *method, double x, double y, double *z)
{
	int			rc;

	*z = value(c->tc.tin, method, x, y, &rc);
	return rc;
}

/* ----------------------------------------------------------------
 *		the parser
 * ----------------------------------------------------------------
 */
static void
test_me_parse(void)
{
	tdc_interp_spec s;
	char		err[256];

	CHECK(tdc_interp_parse("linear", &s, err, sizeof(err)) == TDC_OK && s.max_edge == 0 &&
		  s.options == 0, "max_edge: none by default");
	CHECK(tdc_interp_parse("linear:max_edge=5", &s, err, sizeof(err)) == TDC_OK && s.max_edge == 5 &&
		  s.options == TDC_INTERP_OPT_MAX_EDGE && s.radius == -1, "max_edge: linear:max_edge=5");
	CHECK(tdc_interp_parse("Natural_Neighbor:MAX_EDGE=2.5:nodata=-1", &s, err, sizeof(err)) == TDC_OK &&
		  s.method == TDC_INTERP_NATURAL && s.max_edge == 2.5 && s.nodata == -1 &&
		  s.options == (TDC_INTERP_OPT_MAX_EDGE | TDC_INTERP_OPT_NODATA), "max_edge: natural neighbour, any case");
	CHECK(tdc_interp_parse("nearest:radius1=3:radius2=3:max_edge=7", &s, err, sizeof(err)) == TDC_OK &&
		  s.method == TDC_INTERP_NEAREST && s.max_edge == 7 && s.radius == 3, "max_edge: nearest");
	CHECK(tdc_interp_parse("linear:breaklines=true:max_edge=100", &s, err, sizeof(err)) == TDC_OK &&
		  s.breaklines && s.max_edge == 100, "max_edge: with breaklines");
	CHECK(tdc_interp_parse("linear:max_edge=inf", &s, err, sizeof(err)) == TDC_OK && s.max_edge == 0,
		  "max_edge: infinity is none");
	CHECK(tdc_interp_parse("linear:max_edge=1e-300", &s, err, sizeof(err)) == TDC_OK &&
		  s.max_edge == 0x1p-252, "max_edge: tiny, the smallest exact length");
	CHECK(tdc_interp_parse("linear:max_edge=-1", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "max_edge") && strstr(err, "> 0"), "max_edge -1: %s", err);
	CHECK(tdc_interp_parse("linear:max_edge=0", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "max_edge"), "max_edge 0: %s", err);
	CHECK(tdc_interp_parse("nearest:max_edge=abc", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "\"max_edge\": \"abc\" is not a number"), "max_edge abc: %s", err);
	CHECK(tdc_interp_parse("linear:max_edge", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "no value"), "max_edge without a value: %s", err);
	CHECK(tdc_interp_parse("linear:max_edges=3", &s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "max_edge)"), "an unknown option lists max_edge: %s", err);

	/* contours: linear, max_edge only */
	s = spec_of("linear:max_edge=3");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_OK, "contours take linear:max_edge");
	s = spec_of("linear:breaklines=false:max_edge=3");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_OK, "contours take breaklines=false");
	CHECK(tdc_tin_contours_spec_check(NULL, err, sizeof(err)) == TDC_OK, "contours without a method");
	s = spec_of("nearest:max_edge=3");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_EINVAL && strstr(err, "not nearest"),
		  "contours refuse nearest: %s", err);
	s = spec_of("natural_neighbor");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_EINVAL &&
		  strstr(err, "not natural_neighbor"), "contours refuse natural_neighbor: %s", err);
	s = spec_of("linear:radius=0:max_edge=3");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_EINVAL && strstr(err, "radius"),
		  "contours refuse radius: %s", err);
	s = spec_of("linear:nodata=-1");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_EINVAL && strstr(err, "nodata"),
		  "contours refuse nodata: %s", err);
	s = spec_of("linear:breaklines=true");
	CHECK(tdc_tin_contours_spec_check(&s, err, sizeof(err)) == TDC_EINVAL && strstr(err, "breaklines"),
		  "contours refuse breaklines: %s", err);
}

/* ----------------------------------------------------------------
 *		the exact boundary
 * ----------------------------------------------------------------
 */
static void
one_triangle(const double *xy, double kept, double dropped, const char *name)
{
	double		z[3] = {1, 2, 3},
				pts[6],
				q[2],
				v;
	me_case		c = {{NULL, NULL}, pts, z, 3};
	char		m[96];

	memcpy(pts, xy, sizeof(pts));
	if (!me_mk(&c, 1))
		return;
	q[0] = (xy[0] + xy[2] + xy[4]) / 3;
	q[1] = (xy[1] + xy[3] + xy[5]) / 3;
	snprintf(m, sizeof(m), "linear:max_edge=%.17g", kept);
	CHECK(me_value(&c, m, q[0], q[1], &v) == 1, "%s: kept at max_edge %.17g", name, kept);
	snprintf(m, sizeof(m), "linear:max_edge=%.17g", dropped);
	CHECK(me_value(&c, m, q[0], q[1], &v) == 0 && v == 0, "%s: dropped at max_edge %.17g", name, dropped);
	snprintf(m, sizeof(m), "natural_neighbor:max_edge=%.17g:nodata=-5", dropped);
	CHECK(me_value(&c, m, q[0], q[1], &v) == 0 && v == -5, "%s: natural neighbour dropped too", name);
	/* the corners keep their heights, the hull edges' midpoints do not */
	for (int k = 0; k < 3; k++)
	{
		CHECK(me_value(&c, m, xy[2 * k], xy[2 * k + 1], &v) == 1 && v == z[k],
			  "%s: corner %d keeps its height", name, k);
		CHECK(me_value(&c, m, (xy[2 * k] + xy[(2 * k + 2) % 6]) / 2,
					   (xy[2 * k + 1] + xy[(2 * k + 3) % 6]) / 2, &v) == 0,
			  "%s: no value on hull edge %d", name, k);
	}
	rm(&c.tc);
}

static void
test_me_exact(void)
{
	/* 3, 4, 5: an edge exactly max_edge long is kept */
	{
		double		t[6] = {0, 0, 4, 0, 0, 3};

		one_triangle(t, 5, nextafter(5, 0), "3-4-5 triangle");
	}

	/*
	 * The hypotenuse's squared length is 43.7578...5 + 2.3e-15 above
	 * L^2 for L = 6.614938019361935, the double nearest its length, but
	 * 4.379^2 + 4.958^2 in double rounds to fl(L * L): only the exact
	 * comparison drops it.  The next double keeps it.
	 */
	{
		double		t[6] = {0, 0, 4.379, 0, 4.379, 4.958};

		one_triangle(t, 6.614938019361936, 6.614938019361935, "a near tie");
		CHECK(!(4.379 * 4.379 + 4.958 * 4.958 > 6.614938019361935 * 6.614938019361935),
			  "the near tie is one a double comparison gets wrong");
	}
}

/* ----------------------------------------------------------------
 *		a lake
 * ----------------------------------------------------------------
 */
#define LAKE_N		21			/* lattice 0..20 */
#define LAKE_C		10.0		/* centre */
#define LAKE_R2		36.0		/* no sample within 6, but the centre */
#define LAKE_L		1.5

static double
lake_height(double x, double y)
{
	return 3 * x - 2 * y + 0.25 * x * y;
}

static void
lake_points(me_case *c)
{
	c->xy = malloc(LAKE_N * LAKE_N * 2 * sizeof(double));
	c->z = malloc(LAKE_N * LAKE_N * sizeof(double));
	c->n = 0;
	for (int i = 0; i < LAKE_N; i++)
		for (int j = 0; j < LAKE_N; j++)
		{
			double		dx = i - LAKE_C,
						dy = j - LAKE_C;

			if (dx * dx + dy * dy <= LAKE_R2 && !(dx == 0 && dy == 0))
				continue;
			c->xy[2 * c->n] = i;
			c->xy[2 * c->n + 1] = j;
			c->z[c->n] = lake_height(i, j);
			c->n++;
		}
}

/* exact for the small dyadic coordinates used here */
static double
orient_small(const double *a, const double *b, const double *q)
{
	return (b[0] - a[0]) * (q[1] - a[1]) - (b[1] - a[1]) * (q[0] - a[0]);
}

static bool
long_small(const double *a, const double *b, double l)
{
	return (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]) > l * l;
}

/*
 * The rule, by brute force: q is a site, or some triangle whose closure
 * holds q has no edge longer than l.  Outside the hull: -1 (not decided
 * here).
 */
static int
oracle(const tdc_job *job, const double *q, double l)
{
	tdc_iter	it = {0};
	uint32_t	v[3];
	bool		in_any = false;

	for (size_t s = 0; s < tdc_num_sites(job); s++)
	{
		const double *p = tdc_site_xy(job, (uint32_t) s);

		if (p[0] == q[0] && p[1] == q[1])
			return 1;
	}
	while (tdc_next_triangle(job, &it, v))
	{
		const double *p[3] = {tdc_site_xy(job, v[0]), tdc_site_xy(job, v[1]), tdc_site_xy(job, v[2])};
		int			pos = 0,
					neg = 0;

		for (int k = 0; k < 3; k++)
		{
			double		o = orient_small(p[k], p[(k + 1) % 3], q);

			pos += o > 0;
			neg += o < 0;
		}
		if (pos > 0 && neg > 0)
			continue;
		in_any = true;
		if (!long_small(p[0], p[1], l) && !long_small(p[1], p[2], l) && !long_small(p[2], p[0], l))
			return 1;
	}
	return in_any ? 0 : -1;
}

/* The query points: every site, every edge's midpoint, random dyadic points. */
static double *
lake_queries(const me_case *c, size_t *nq)
{
	tdc_iter	it = {0};
	uint32_t	e[2];
	uint64_t	seed = 39;
	size_t		cap = c->n + 4 * tdc_num_edges(c->tc.job) + 2000,
				n = 0;
	double	   *q = malloc(cap * 2 * sizeof(double));

	for (size_t s = 0; s < tdc_num_sites(c->tc.job); s++)
	{
		memcpy(q + 2 * n, tdc_site_xy(c->tc.job, (uint32_t) s), 2 * sizeof(double));
		n++;
	}
	while (tdc_next_edge(c->tc.job, &it, e))
	{
		const double *a = tdc_site_xy(c->tc.job, e[0]),
				   *b = tdc_site_xy(c->tc.job, e[1]);

		q[2 * n] = (a[0] + b[0]) / 2;
		q[2 * n + 1] = (a[1] + b[1]) / 2;
		n++;
	}
	for (int i = 0; i < 2000; i++)
	{
		q[2 * n] = floor(tdc_splitmix_unit(&seed) * 20 * 64) / 64;
		q[2 * n + 1] = floor(tdc_splitmix_unit(&seed) * 20 * 64) / 64;
		n++;
	}
	*nq = n;
	return q;
}

static void
test_me_lake(void)
{
	static const char *const methods[3] = {"linear", "nearest", "natural_neighbor"};
	me_case		c;
	double	   *q;
	size_t		nq;

	lake_points(&c);
	if (!me_mk(&c, 2))
		return;
	q = lake_queries(&c, &nq);
	for (int m = 0; m < 3; m++)
	{
		char		with[64],
					without[64];
		size_t		bad_valid = 0,
					bad_value = 0,
					holes = 0;
		double	   *v1 = malloc(nq * sizeof(double)),
				   *v0 = malloc(nq * sizeof(double));
		uint8_t    *ok1 = malloc(nq),
				   *ok0 = malloc(nq);
		char		err[256];
		tdc_interp_spec s1,
					s0;

		snprintf(with, sizeof(with), "%s:max_edge=%g:nodata=-999", methods[m], LAKE_L);
		snprintf(without, sizeof(without), "%s:nodata=-999", methods[m]);
		s1 = spec_of(with);
		s0 = spec_of(without);
		if (run_wait(c.tc.tin, tdc_tin_points_start(c.tc.tin, &s0, q, nq, v0, ok0, err, sizeof(err)), err) == TDC_OK &&
			run_wait(c.tc.tin, tdc_tin_points_start(c.tc.tin, &s1, q, nq, v1, ok1, err, sizeof(err)), err) == TDC_OK)
		{
			for (size_t i = 0; i < nq; i++)
			{
				int			want = oracle(c.tc.job, q + 2 * i, LAKE_L);

				if (want < 0)
					continue;
				if (ok1[i] != want)
				{
					if (bad_valid++ < 5)
						fprintf(stderr, "  %s at (%g %g): valid %d, the rule says %d\n", with,
								q[2 * i], q[2 * i + 1], ok1[i], want);
				}
				else if (want ? (!ok0[i] || v1[i] != v0[i]) : v1[i] != -999)
					bad_value++;
				holes += !want;
			}
			printf("tin: max_edge: %s: %zu of %zu points in the hole, %zu unlike the rule\n", with, holes, nq,
				   bad_valid);
			CHECK(bad_valid == 0 && bad_value == 0 && holes > 100,
				  "%s: a value exactly where the rule says (%zu of %zu points in the hole, %zu wrong, "
				  "%zu values unlike the method's)", with, holes, nq, bad_valid, bad_value);
		}
		free(v1);
		free(v0);
		free(ok1);
		free(ok0);
	}

	/* the sample in the lake keeps its height; beside it, nothing */
	for (int m = 0; m < 3; m++)
	{
		char		with[64];
		double		v;

		snprintf(with, sizeof(with), "%s:max_edge=%g", methods[m], LAKE_L);
		CHECK(me_value(&c, with, LAKE_C, LAKE_C, &v) == 1 && v == lake_height(LAKE_C, LAKE_C),
			  "%s: the sample in the lake keeps its height", with);
		CHECK(me_value(&c, with, LAKE_C + 0.125, LAKE_C, &v) == 0, "%s: none beside it", with);
		CHECK(me_value(&c, methods[m], LAKE_C + 0.125, LAKE_C, &v) == 1, "%s: a value there without it",
			  methods[m]);
		/* outside the hull: the radius rule, unchanged */
		CHECK(me_value(&c, with, -1, 5, &v) == 1 && v == lake_height(0, 5),
			  "%s: outside the hull, the nearest sample at any distance (radius -1)", with);
	}
	{
		double		v;

		CHECK(me_value(&c, "linear:max_edge=1.5:radius=0", -1, 5, &v) == 0,
			  "linear:max_edge:radius=0: no value outside the hull");
		/* a lake edge between two samples on a row: (9, 4)-(11, 4), 2 long */
		CHECK(me_value(&c, "linear:max_edge=1.5", 10, 4, &v) == 0, "no value on an edge longer than max_edge");
		CHECK(me_value(&c, "linear:max_edge=2", 10, 4, &v) == 1, "... a value at max_edge 2, its length");
		/* an edge between the lattice (kept) and the lake (dropped) */
		CHECK(me_value(&c, "linear:max_edge=1.5", 7.5, 4, &v) == 1 && v == lake_height(7.5, 4),
			  "a value on an edge between a kept and a dropped triangle");
	}

	/* a grid: the same for 1 and 3 threads, and the hole as the rule says */
	{
		tdc_grid_spec g = {{-0.5, 0.25, 0, 20.5, 0, -0.25}, 84, 84};
		tdc_interp_spec s = spec_of("natural_neighbor:max_edge=1.5:nodata=-1");
		double	   *a = malloc(84 * 84 * sizeof(double)),
				   *b = malloc(84 * 84 * sizeof(double));
		uint8_t    *oka = malloc(84 * 84),
				   *okb = malloc(84 * 84);
		size_t		bad = 0,
					holes = 0;
		char		err[256];
		me_case		c3 = c;

		if (run_wait(c.tc.tin, tdc_tin_grid_start(c.tc.tin, &s, &g, a, oka, err, sizeof(err)), err) == TDC_OK &&
			me_mk(&c3, 3) &&
			run_wait(c3.tc.tin, tdc_tin_grid_start(c3.tc.tin, &s, &g, b, okb, err, sizeof(err)), err) == TDC_OK)
		{
			for (int r = 0; r < 84; r++)
				for (int col = 0; col < 84; col++)
				{
					double		p[2] = {-0.5 + (col + 0.5) * 0.25, 20.5 - (r + 0.5) * 0.25};
					int			want = oracle(c.tc.job, p, LAKE_L);

					if (want >= 0)
					{
						bad += oka[r * 84 + col] != want;
						holes += !want;
					}
				}
			CHECK(bad == 0 && holes > 400, "grid: the hole where the rule says (%zu pixels, %zu wrong)",
				  holes, bad);
			CHECK(memcmp(a, b, 84 * 84 * sizeof(double)) == 0 && memcmp(oka, okb, 84 * 84) == 0,
				  "grid with max_edge: the same for 1 and 3 threads");
		}
		if (c3.tc.tin != c.tc.tin)
			rm(&c3.tc);
		free(a);
		free(b);
		free(oka);
		free(okb);
	}
	free(q);
	rm(&c.tc);
	free(c.xy);
	free(c.z);
}

/* Collinear samples: the segment between two neighbours plays the triangle. */
static void
test_me_collinear(void)
{
	double		xy[8] = {0, 0, 1, 0, 5, 0, 6, 0},
				z[4] = {1, 2, 3, 4},
				v;
	me_case		c = {{NULL, NULL}, xy, z, 4};

	if (!me_mk(&c, 1))
		return;
	CHECK(me_value(&c, "linear:max_edge=2", 0.5, 0, &v) == 1 && v == 1.5, "collinear: a short segment");
	CHECK(me_value(&c, "linear:max_edge=2", 3, 0, &v) == 0, "collinear: a long segment has no value");
	CHECK(me_value(&c, "linear:max_edge=4", 3, 0, &v) == 1 && v == 2.5, "collinear: exactly max_edge long");
	CHECK(me_value(&c, "linear:max_edge=2", 5, 0, &v) == 1 && v == 3, "collinear: a site keeps its height");
	CHECK(me_value(&c, "nearest:max_edge=2", 3, 0, &v) == 0, "collinear: nearest masked the same way");
	rm(&c.tc);
}

/* ----------------------------------------------------------------
 *		contours
 * ----------------------------------------------------------------
 */

typedef struct me_lines
{
	size_t		n,
				closed,
				open_ends_ok,
				open;
	double		worst;			/* relative length error of a level */
	double	   *flat;			/* every line: level, n, closed, points */
	size_t		nflat;
} me_lines;

static void
contours_of(me_case *c, const char *method, double interval, me_lines *st)
{
	tdc_interp_spec s = spec_of(method);
	char		err[256];
	size_t		nl,
				np,
				i = 0;

	memset(st, 0, sizeof(*st));
	if (run_wait(c->tc.tin, tdc_tin_contours_start_spec(c->tc.tin, interval, 0.5, &s, err, sizeof(err)), err) != TDC_OK)
		return;
	nl = tdc_tin_contour_count(c->tc.tin, &np);
	st->n = nl;
	st->flat = malloc((3 * nl + 2 * np + 1) * sizeof(double));
	while (i < nl)
	{
		double		lev = 0,
					len = 0,
					want;
		size_t		j = i;

		for (; j < nl; j++)
		{
			double		l2;
			size_t		n;
			bool		closed;
			const double *p = tdc_tin_contour_line(c->tc.tin, j, &l2, &n, &closed);

			if (j == i)
				lev = l2;
			if (l2 != lev)
				break;
			st->flat[st->nflat++] = l2;
			st->flat[st->nflat++] = (double) n;
			st->flat[st->nflat++] = closed;
			memcpy(st->flat + st->nflat, p, 2 * n * sizeof(double));
			st->nflat += 2 * n;
			for (size_t k = 0; k + 1 < n; k++)
				len += hypot(p[2 * k + 2] - p[2 * k], p[2 * k + 3] - p[2 * k + 1]);
			if (closed)
				st->closed++;
			else
			{
				/* each end: on the hull or where the kept triangles end */
				st->open++;
				for (int e = 0; e < 2; e++)
				{
					const double *q = e == 0 ? p : p + 2 * (n - 1);
					int			none = 0;

					for (int k = 0; k < 8; k++)
					{
						double		a = k * M_PI / 4,
									pr[2] = {q[0] + 1e-7 * cos(a), q[1] + 1e-7 * sin(a)},
									zz;

						none += tdc_tin_value(c->tc.tin, &s, pr, &zz) == 0 || !tdc_tin_inside(c->tc.tin, pr);
					}
					st->open_ends_ok += none > 0;
				}
			}
		}
		want = level_length(c->tc.job, c->z, lev, s.max_edge);
		st->worst = fmax(st->worst, fabs(len - want) / fmax(want, 1e-300));
		i = j;
	}
}

static void
test_me_contours(void)
{
	me_case		c,
				c3;
	me_lines	a,
				b,
				plain;

	lake_points(&c);
	/* z = x: every level a vertical line, those through the lake cut in two */
	for (size_t i = 0; i < c.n; i++)
		c.z[i] = c.xy[2 * i];
	if (!me_mk(&c, 2))
		return;
	contours_of(&c, "linear", 1, &plain);
	contours_of(&c, "linear:max_edge=1.5", 1, &a);
	CHECK(plain.n == 20 && plain.open == 20 && plain.worst < 1e-12,
		  "contours of z = x: 20 straight lines (%zu, %zu open, length error %g)", plain.n, plain.open,
		  plain.worst);
	{
		/* the pieces of each line x = L the rule keeps, by the oracle every 1/64 along it */
		size_t		want = 0;

		for (int k = 0; k < 20; k++)
		{
			bool		in = false;

			for (int j = 0; j <= 20 * 64; j++)
			{
				double		p[2] = {k + 0.5, j / 64.0};
				bool		v = oracle(c.tc.job, p, LAKE_L) == 1;

				want += v && !in;
				in = v;
			}
		}
		printf("tin: max_edge: contours of z = x: 20 lines without it, %zu with it\n", a.n);
		CHECK(want > 20 && a.n == want && a.open == want && a.open_ends_ok == 2 * want && a.worst < 1e-12,
			  "contours of z = x with max_edge: the lines through the lake cut where the kept triangles "
			  "end (%zu lines, %zu pieces by the rule, %zu open, %zu ends on the boundary, length error %g)",
			  a.n, want, a.open, a.open_ends_ok, a.worst);
	}
	free(plain.flat);
	free(a.flat);
	rm(&c.tc);

	/* a cone around the lake: rings beyond it closed, the others open or gone */
	for (size_t i = 0; i < c.n; i++)
		c.z[i] = -hypot(c.xy[2 * i] - LAKE_C, c.xy[2 * i + 1] - LAKE_C);
	c3 = c;
	if (!me_mk(&c, 1) || !me_mk(&c3, 3))
		return;
	contours_of(&c, "linear", 0.75, &plain);
	contours_of(&c, "linear:max_edge=1.5", 0.75, &a);
	contours_of(&c3, "linear:max_edge=1.5", 0.75, &b);
	printf("tin: max_edge: contours of a cone around the lake: %zu lines (%zu closed) without it, %zu "
		   "(%zu closed, %zu open) with it\n", plain.n, plain.closed, a.n, a.closed, a.open);
	CHECK(plain.closed > a.closed && a.closed >= 4 && a.open_ends_ok == 2 * a.open && a.worst < 1e-12,
		  "contours of a cone with max_edge: %zu closed rings of %zu without it, %zu open lines, every end "
		  "on the kept region's boundary, length error %g", a.closed, plain.closed, a.open, a.worst);
	CHECK(a.nflat == b.nflat && memcmp(a.flat, b.flat, a.nflat * sizeof(double)) == 0,
		  "contours with max_edge: the same for 1 and 3 threads");
	free(plain.flat);
	free(a.flat);
	free(b.flat);
	rm(&c.tc);
	rm(&c3.tc);
	free(c.xy);
	free(c.z);
}

/*
 * Many lakes on a lattice of 360 x 360 samples (about 250,000 triangles,
 * several ranges of the contours' passes, on the pool's threads): contour
 * lengths per level against the sum over the kept triangles, and the
 * lines, a grid and a drape the same for 1 and 3 threads.
 */
static void
test_me_many_lakes(void)
{
	int			side = tdc_test_quick ? 160 : 360;
	uint64_t	seed = 3924;
	double		lakes[24][3];
	me_case		c1,
				c3;
	me_lines	a,
				b;
	size_t		n = 0;

	for (int k = 0; k < 24; k++)
	{
		lakes[k][0] = tdc_splitmix_unit(&seed) * side;
		lakes[k][1] = tdc_splitmix_unit(&seed) * side;
		lakes[k][2] = 2 + tdc_splitmix_unit(&seed) * side / 20.0;
	}
	c1.xy = malloc((size_t) side * side * 2 * sizeof(double));
	c1.z = malloc((size_t) side * side * sizeof(double));
	for (int i = 0; i < side; i++)
		for (int j = 0; j < side; j++)
		{
			bool		wet = false;

			for (int k = 0; k < 24; k++)
				wet |= hypot(i - lakes[k][0], j - lakes[k][1]) < lakes[k][2];
			if (wet)
				continue;
			c1.xy[2 * n] = i;
			c1.xy[2 * n + 1] = j;
			c1.z[n] = 50 * sin(i / 37.0) * cos(j / 23.0) + 0.1 * i;
			n++;
		}
	c1.n = n;
	c3 = c1;
	if (me_mk(&c1, 1) && me_mk(&c3, 3))
	{
		tdc_grid_spec g = {{0, 0.7, 0, side, 0, -0.7}, (size_t) (side / 0.7), (size_t) (side / 0.7)};
		tdc_interp_spec s = spec_of("linear:max_edge=1.5");
		size_t		np = g.width * g.height,
					empty = 0;
		double	   *v1 = malloc(np * sizeof(double)),
				   *v3 = malloc(np * sizeof(double));
		uint8_t    *ok1 = malloc(np),
				   *ok3 = malloc(np);
		char		err[256];

		contours_of(&c1, "linear:max_edge=1.5", 7, &a);
		contours_of(&c3, "linear:max_edge=1.5", 7, &b);
		printf("tin: max_edge: %zu samples with 24 lakes: %zu contour lines (%zu closed, %zu open), length "
			   "error %g\n", n, a.n, a.closed, a.open, a.worst);
		CHECK(a.n > 20 && a.open > 0 && a.open_ends_ok == 2 * a.open && a.worst < 1e-9,
			  "many lakes: contour lengths over the kept triangles (error %g), every open end on a boundary",
			  a.worst);
		CHECK(a.nflat == b.nflat && memcmp(a.flat, b.flat, a.nflat * sizeof(double)) == 0,
			  "many lakes: the same contour lines for 1 and 3 threads");
		if (run_wait(c1.tc.tin, tdc_tin_grid_start(c1.tc.tin, &s, &g, v1, ok1, err, sizeof(err)), err) == TDC_OK &&
			run_wait(c3.tc.tin, tdc_tin_grid_start(c3.tc.tin, &s, &g, v3, ok3, err, sizeof(err)), err) == TDC_OK)
		{
			for (size_t i = 0; i < np; i++)
				empty += !ok1[i];
			CHECK(empty > np / 100 && memcmp(v1, v3, np * sizeof(double)) == 0 && memcmp(ok1, ok3, np) == 0,
				  "many lakes: a grid of %zu pixels, %zu empty, the same for 1 and 3 threads", np, empty);
		}
		free(a.flat);
		free(b.flat);
		free(v1);
		free(v3);
		free(ok1);
		free(ok3);
	}
	rm(&c1.tc);
	rm(&c3.tc);
	free(c1.xy);
	free(c1.z);
}

/* ----------------------------------------------------------------
 *		draping
 * ----------------------------------------------------------------
 */

/* Drape one segment; the output vertices and how many have gap set. */
static size_t
drape_one(me_case *c, const char *method, double x0, double y0, double x1, double y1,
		  const tdc_drape_vertex **out, size_t *ngap, size_t *ninvalid)
{
	tdc_interp_spec s = spec_of(method);
	double		xy[4] = {x0, y0, x1, y1};
	size_t		end = 2,
				nv;
	const size_t *off;
	char		err[256];

	*ngap = *ninvalid = 0;
	if (run_wait(c->tc.tin, tdc_tin_drape_start(c->tc.tin, &s, xy, &end, 1, err, sizeof(err)), err) != TDC_OK)
		return 0;
	nv = tdc_tin_drape_result(c->tc.tin, out, &off);
	for (size_t i = 0; i < nv; i++)
	{
		*ngap += (*out)[i].gap;
		*ninvalid += !(*out)[i].valid;
	}
	return nv;
}

static void
test_me_drape(void)
{
	me_case		c;
	const tdc_drape_vertex *v;
	size_t		nv,
				ngap,
				ninv,
				first = 0;

	lake_points(&c);
	if (!me_mk(&c, 2))
		return;

	/* across the lake: pieces inside it marked, the ends valued */
	nv = drape_one(&c, "linear:max_edge=1.5", 2.25, 10.125, 17.75, 9.875, &v, &ngap, &ninv);
	while (first < nv && !v[first].gap)
		first++;
	CHECK(nv > 10 && ngap > 0 && ninv > 0 && v[0].valid && v[nv - 1].valid && first < nv &&
		  v[first].x > 3 && v[first].x < 5,
		  "drape across the lake: %zu pieces marked, %zu crossings without a value, the first from "
		  "x = %g, at the lake's shore", ngap, ninv, first < nv ? v[first].x : NAN);
	nv = drape_one(&c, "linear", 2.25, 10.125, 17.75, 9.875, &v, &ngap, &ninv);
	CHECK(nv > 10 && ngap == 0 && ninv == 0, "the same without max_edge: no piece marked");

	/* along a row of samples: (9, 4)-(11, 4) is 2 long, both its triangles dropped */
	nv = drape_one(&c, "linear:max_edge=1.5", 2, 4, 18, 4, &v, &ngap, &ninv);
	first = 0;
	while (first < nv && !v[first].gap)
		first++;
	CHECK(ngap == 1 && first < nv && v[first].x == 9 && v[first].y == 4 && ninv == 0,
		  "drape along a row: only the piece along the long edge from (9 4) marked (%zu marked)", ngap);
	/* along edges between the lattice (kept) and the lake (dropped) */
	nv = drape_one(&c, "linear:max_edge=1.5", 2, 4, 8, 4, &v, &ngap, &ninv);
	CHECK(nv == 7 && ngap == 0 && ninv == 0,
		  "drape along edges beside the lake: nothing marked (%zu vertices, %zu marked)", nv, ngap);
	/* beside the lake: the same vertices as without the option */
	{
		tdc_drape_vertex *keep;
		size_t		n0;

		n0 = drape_one(&c, "linear", 0.3, 0.7, 19.6, 2.2, &v, &ngap, &ninv);
		keep = malloc(n0 * sizeof(*keep) + 1);
		memcpy(keep, v, n0 * sizeof(*keep));
		nv = drape_one(&c, "linear:max_edge=1.5", 0.3, 0.7, 19.6, 2.2, &v, &ngap, &ninv);
		CHECK(nv == n0 && n0 > 20 && ngap == 0 && ninv == 0 && memcmp(v, keep, nv * sizeof(*keep)) == 0,
			  "drape beside the lake: the vertices without max_edge (%zu)", nv);
		free(keep);
	}
	/* vertices: in the lake none, at its sample its height */
	nv = drape_one(&c, "natural_neighbor:max_edge=1.5", 9.5, 9.25, 10, 10, &v, &ngap, &ninv);
	CHECK(nv == 2 && !v[0].valid && v[1].valid && v[1].z == lake_height(10, 10) && ngap == 0,
		  "drape with natural neighbour: a vertex in the lake has no value, its sample has");
	rm(&c.tc);
	free(c.xy);
	free(c.z);

	/* collinear samples: the long segment between 1 and 5 */
	{
		double		xy[8] = {0, 0, 1, 0, 5, 0, 6, 0},
					z[4] = {1, 2, 3, 4};
		me_case		l = {{NULL, NULL}, xy, z, 4};

		if (me_mk(&l, 1))
		{
			nv = drape_one(&l, "linear:max_edge=2", 0.5, 0, 5.5, 0, &v, &ngap, &ninv);
			CHECK(nv == 4 && ngap == 1 && v[1].x == 1 && v[1].gap && ninv == 0,
				  "collinear drape: the piece from the sample at 1 to the one at 5 marked (%zu vertices)", nv);
			nv = drape_one(&l, "linear:max_edge=2", 5.5, 0, 0.5, 0, &v, &ngap, &ninv);
			CHECK(nv == 4 && ngap == 1 && v[1].x == 5 && v[1].gap,
				  "collinear drape, backwards: the piece from the sample at 5 marked");
			nv = drape_one(&l, "linear:max_edge=2", 2, 0, 3, 0, &v, &ngap, &ninv);
			CHECK(nv == 2 && ninv == 2 && ngap == 1 && v[0].gap,
				  "collinear drape within the long segment: no value, marked");
			rm(&l.tc);
		}
	}
}

void
test_tin_maxedge(void)
{
	test_me_parse();
	test_me_exact();
	test_me_lake();
	test_me_collinear();
	test_me_contours();
	test_me_many_lakes();
	test_me_drape();
}
