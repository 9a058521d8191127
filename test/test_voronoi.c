/*
 * test_voronoi.c
 *		The Voronoi cells (voronoi*.c): the circumcenter against exact
 *		rational arithmetic (GMP), and the cells' validity on uniform,
 *		clustered, lattice, collinear, duplicated, tiny, huge and
 *		border-touching inputs.
 *
 * For every diagram: each site has a cell; each cell is a ring of at least
 * three vertices with no repeated consecutive vertex, turning left or going
 * straight at every vertex (exact orientation) and winding once, so it is a
 * simple convex polygon; it contains its site (exactly); it lies inside the
 * clip envelope; the cell areas add up to the envelope's area; and every
 * cell edge that is not on the envelope's boundary appears reversed, with
 * bit-identical end points, in exactly one other cell, so the cells form a
 * coverage whose shared vertices are the same doubles.  The threaded build
 * must give the same rings as the single-threaded one.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <gmp.h>

#include "harness.h"
#include "engine/predicates.h"
#include "tdc.h"

static uint64_t vrng_state;

static uint64_t
vrng(void)
{
	uint64_t	z = (vrng_state += 0x9E3779B97F4A7C15ull);

	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
	return z ^ (z >> 31);
}

static double
vurand(void)
{
	return (vrng() >> 11) * 0x1p-53;
}

/* ---------------- circumcenter against GMP ---------------- */

/* |computed - exact| for one coordinate, as a double (exact difference rounded). */
static double
abs_err(double computed, const mpq_t exact)
{
	mpq_t		d;
	double		r;

	if (!isfinite(computed))
		return INFINITY;
	mpq_init(d);
	mpq_set_d(d, computed);
	mpq_sub(d, d, exact);
	mpq_abs(d, d);
	r = mpq_get_d(d);
	mpq_clear(d);
	return r;
}

/*
 * Check one triangle: returns the ratio of the error to the documented bound
 * (<= 1 passes).
 */
static double
check_circumcenter(const double *a, const double *b, const double *c)
{
	mpq_t		bx, by, cx, cy, B, C, D, t, ux, uy, X, Y;
	double		out[2], ratio = 0;
	double		L, Dd, K, u;

	tdc_circumcenter(a, b, c, out);
	mpq_inits(bx, by, cx, cy, B, C, D, t, ux, uy, X, Y, NULL);
	mpq_set_d(bx, b[0]); mpq_set_d(t, a[0]); mpq_sub(bx, bx, t);
	mpq_set_d(by, b[1]); mpq_set_d(t, a[1]); mpq_sub(by, by, t);
	mpq_set_d(cx, c[0]); mpq_set_d(t, a[0]); mpq_sub(cx, cx, t);
	mpq_set_d(cy, c[1]); mpq_set_d(t, a[1]); mpq_sub(cy, cy, t);
	mpq_mul(B, bx, bx); mpq_mul(t, by, by); mpq_add(B, B, t);
	mpq_mul(C, cx, cx); mpq_mul(t, cy, cy); mpq_add(C, C, t);
	mpq_mul(D, bx, cy); mpq_mul(t, by, cx); mpq_sub(D, D, t);
	/* ux = (cy B - by C) / 2D, uy = (bx C - cx B) / 2D */
	mpq_mul(ux, cy, B); mpq_mul(t, by, C); mpq_sub(ux, ux, t);
	mpq_mul(uy, bx, C); mpq_mul(t, cx, B); mpq_sub(uy, uy, t);
	mpq_add(t, D, D);
	mpq_div(ux, ux, t);
	mpq_div(uy, uy, t);
	mpq_set_d(X, a[0]); mpq_add(X, X, ux);
	mpq_set_d(Y, a[1]); mpq_add(Y, Y, uy);

	L = fmax(sqrt(mpq_get_d(B)), sqrt(mpq_get_d(C)));
	Dd = fabs(mpq_get_d(D));
	K = (fabs(mpq_get_d(bx) * mpq_get_d(cy)) + fabs(mpq_get_d(by) * mpq_get_d(cx))) / Dd;
	u = fmax(fabs(mpq_get_d(ux)), fabs(mpq_get_d(uy)));
	for (int k = 0; k < 2; k++)
	{
		double		exact = mpq_get_d(k ? Y : X);
		double		bound = 0.5 * (nextafter(fabs(exact), INFINITY) - fabs(exact)) +
			0x1p-98 * (L * L * L / Dd + K * u);
		double		err = abs_err(out[k], k ? Y : X);

		/* 1/2 ulp of the result: use the larger ulp of exact and computed */
		bound = fmax(bound, 0.5 * (nextafter(fabs(out[k]), INFINITY) - fabs(out[k])) +
					 0x1p-98 * (L * L * L / Dd + K * u));
		if (err / bound > ratio)
			ratio = err / bound;
		/*
		 * And per coordinate: 1/2 ulp plus 2^-56 of itself (the exact path
		 * takes over where double-double cannot promise that), so a
		 * coordinate near 0 is not swamped by the other's size.
		 */
		bound = 0.5 * fmax(nextafter(fabs(exact), INFINITY) - fabs(exact),
						   nextafter(fabs(out[k]), INFINITY) - fabs(out[k])) +
			0x1p-55 * fabs(exact);
		if (err / bound > ratio)
			ratio = err / bound;
	}
	mpq_clears(bx, by, cx, cy, B, C, D, t, ux, uy, X, Y, NULL);
	return ratio;
}

/* Is r the double nearest to x (a tie either way)?  Exact. */
static bool
nearest_double(double r, const mpq_t x)
{
	mpq_t		lo,
				hi,
				t;
	bool		ok;

	mpq_inits(lo, hi, t, NULL);
	mpq_set_d(lo, nextafter(r, -INFINITY));
	mpq_set_d(hi, nextafter(r, INFINITY));
	mpq_set_d(t, r);
	mpq_add(lo, lo, t);
	mpq_add(hi, hi, t);
	mpq_set_ui(t, 2, 1);
	mpq_div(lo, lo, t);
	mpq_div(hi, hi, t);
	ok = mpq_cmp(lo, x) <= 0 && mpq_cmp(x, hi) <= 0;
	mpq_clears(lo, hi, t, NULL);
	return ok;
}

/*
 * The circumcenter of a well shaped triangle, as a million points make,
 * is the exact one correctly rounded: the plain double path proves it
 * before it answers, and the careful path is only further off than that
 * within 2^-56 of a rounding boundary.  Sites an offset away from 0 of a
 * few hundred to a million times their spacing, as uniform input is.
 */
static void
test_circumcenter_rounding(void)
{
	int			bad = 0,
				n = 0;

	vrng_state = 4321;
	for (int i = 0; i < 20000; i++)
	{
		double		p[3][2],
					spacing = ldexp(1.0, (int) (vrng() % 200) - 100),
					off = spacing * ldexp(1.0, 8 + (int) (vrng() % 13));
		mpq_t		bx, by, cx, cy, B, C, D, t, u;
		double		out[2];

		for (int k = 0; k < 3; k++)
		{
			p[k][0] = off * (vurand() + 0.5) + 0;
			p[k][1] = off * (vurand() - 1.5);
		}
		for (int k = 1; k < 3; k++)
		{
			p[k][0] = p[0][0] + spacing * (vurand() - 0.5);
			p[k][1] = p[0][1] + spacing * (vurand() - 0.5);
		}
		if (tdc_orient2d(p[0], p[1], p[2]) <= 0)
			continue;
		tdc_circumcenter(p[0], p[1], p[2], out);
		mpq_inits(bx, by, cx, cy, B, C, D, t, u, NULL);
		mpq_set_d(bx, p[1][0]); mpq_set_d(t, p[0][0]); mpq_sub(bx, bx, t);
		mpq_set_d(by, p[1][1]); mpq_set_d(t, p[0][1]); mpq_sub(by, by, t);
		mpq_set_d(cx, p[2][0]); mpq_set_d(t, p[0][0]); mpq_sub(cx, cx, t);
		mpq_set_d(cy, p[2][1]); mpq_set_d(t, p[0][1]); mpq_sub(cy, cy, t);
		mpq_mul(B, bx, bx); mpq_mul(t, by, by); mpq_add(B, B, t);
		mpq_mul(C, cx, cx); mpq_mul(t, cy, cy); mpq_add(C, C, t);
		mpq_mul(D, bx, cy); mpq_mul(t, by, cx); mpq_sub(D, D, t);
		mpq_add(D, D, D);
		for (int k = 0; k < 2; k++)
		{
			if (k == 0)
			{
				mpq_mul(u, cy, B); mpq_mul(t, by, C); mpq_sub(u, u, t);
			}
			else
			{
				mpq_mul(u, bx, C); mpq_mul(t, cx, B); mpq_sub(u, u, t);
			}
			mpq_div(u, u, D);
			mpq_set_d(t, p[0][k]);
			mpq_add(u, u, t);
			if (!nearest_double(out[k], u))
				bad++;
		}
		mpq_clears(bx, by, cx, cy, B, C, D, t, u, NULL);
		n++;
	}
	CHECK(bad == 0 && n > 9000,
		  "circumcenters of well shaped triangles: %d of %d coordinates not correctly rounded",
		  bad, 2 * n);
}

static void
test_circumcenters(void)
{
	double		worst = 0;
	int			bad = 0,
				n = 0;

	vrng_state = 1234;
	for (int i = 0; i < 20000; i++)
	{
		double		p[3][2],
					scale = ldexp(1.0, (int) (vrng() % 380) - 190);
		double		off = (vrng() & 1) ? scale * 1e6 * (vurand() - 0.5) : 0;
		int			kind = i % 5;
		double		r;

		for (int k = 0; k < 3; k++)
		{
			p[k][0] = off + scale * (vurand() - 0.5);
			p[k][1] = off + scale * (vurand() - 0.5);
		}
		if (kind == 1)
		{
			/* skinny: c near the line ab */
			double		t = vurand();

			p[2][0] = p[0][0] + t * (p[1][0] - p[0][0]) + scale * 1e-9 * (vurand() - 0.5);
			p[2][1] = p[0][1] + t * (p[1][1] - p[0][1]) + scale * 1e-9 * (vurand() - 0.5);
		}
		else if (kind == 2)
		{
			/* nearly collinear: a few ulps off the line */
			p[2][0] = p[0][0] * 0.5 + p[1][0] * 0.5;
			p[2][1] = nextafter(p[0][1] * 0.5 + p[1][1] * 0.5, INFINITY);
		}
		else if (kind == 3)
		{
			/* small integers: many exact, cocircular-like centers */
			for (int k = 0; k < 3; k++)
			{
				p[k][0] = (double) (vrng() % 64);
				p[k][1] = (double) (vrng() % 64);
			}
		}
		else if (kind == 4)
		{
			/*
			 * near-duplicates under a far site: b and c up to 2^-200 of
			 * the scale apart, a up to 2^60 times farther (a triangle
			 * 2^-250 thin made D vanish in double-double: NaN)
			 */
			double		far = ldexp(scale, (int) (vrng() % 61)),
						d = ldexp(scale, -(int) (vrng() % 201));

			p[0][0] = off + far * (vurand() - 0.5);
			p[0][1] = off + far * (vurand() + 0.5);
			p[2][0] = p[1][0] + d * (vurand() - 0.5);
			p[2][1] = p[1][1] + d * (vurand() - 0.5);
			if (fabs(p[0][0]) > 1e60 || fabs(p[0][1]) > 1e60)
				continue;
		}
		if (tdc_orient2d(p[0], p[1], p[2]) == 0)
			continue;
		if (tdc_orient2d(p[0], p[1], p[2]) < 0)
		{
			double		t[2] = {p[1][0], p[1][1]};

			p[1][0] = p[2][0], p[1][1] = p[2][1];
			p[2][0] = t[0], p[2][1] = t[1];
		}
		r = check_circumcenter(p[0], p[1], p[2]);
		n++;
		if (r > worst)
			worst = r;
		if (r > 1)
			bad++;
	}
	CHECK(bad == 0 && n > 15000,
		  "circumcenter error bound: %d of %d triangles over it, worst ratio %g", bad, n, worst);
	printf("voronoi: circumcenter worst error / bound %.3g over %d triangles\n", worst, n);
}

/* ---------------- cells ---------------- */

/*
 * Near-degenerate input (lattices nudged by ulps, sites an ulp apart): a
 * cell narrower than the spacing of doubles cannot be represented; once its
 * vertices are rounded it may turn right by an ulp, collapse to a sliver of
 * zero area (a ring of 2 vertices, or one that winds 0 times), or miss its
 * site by an ulp.  In this mode those are counted (and printed), not
 * failed; containment still must hold within 1e-12 of the envelope's size,
 * and edge sharing and the area sum hold as everywhere.
 */
static bool vor_near_degenerate;

/* the merge tolerance of check_diagram's triangulations */
static double vor_tolerance = 0;

/*
 * Is q inside the ring (crossing count), or within tol of its boundary?
 * For near-degenerate cells, whose rounded rings may zigzag by an ulp, where
 * the per-edge orientation test of a convex ring does not apply.
 */
static bool
near_ring(const double *c, size_t m, const double *q, double tol)
{
	bool		in = false;
	double		best = INFINITY;

	for (size_t i = 0, j = m - 1; i < m; j = i++)
	{
		const double *a = c + 2 * i,
				   *b = c + 2 * j;
		double		dx = b[0] - a[0],
					dy = b[1] - a[1],
					len2 = dx * dx + dy * dy,
					t = len2 > 0 ? ((q[0] - a[0]) * dx + (q[1] - a[1]) * dy) / len2 : 0;

		if ((a[1] > q[1]) != (b[1] > q[1]) &&
			q[0] < a[0] + (q[1] - a[1]) * dx / dy)
			in = !in;
		t = fmin(fmax(t, 0), 1);
		best = fmin(best, hypot(q[0] - (a[0] + t * dx), q[1] - (a[1] + t * dy)));
	}
	return in || best <= tol;
}

typedef struct dedge
{
	double		p[2],
				q[2];
	bool		sliver;			/* from a cell collapsed by rounding */
} dedge;

static int
cmp_dedge(const void *x, const void *y)
{
	return memcmp(x, y, 4 * sizeof(double));
}

static bool
on_env_side(const double *env, const double *p, const double *q)
{
	return (p[0] == env[0] && q[0] == env[0]) || (p[0] == env[2] && q[0] == env[2]) ||
		(p[1] == env[1] && q[1] == env[1]) || (p[1] == env[3] && q[1] == env[3]);
}

/* ---------------- the cells written through tdc_voronoi_emit ---------------- */

/* A test layout: the vertex count, a pad, the ring, its first vertex again. */
static size_t
test_cell_size(void *arg, size_t m)
{
	return 8 + 16 * (m + 1);
}

static void
test_cell_write(void *arg, char *dst, const double *xy, size_t m)
{
	uint32_t	h[2] = {(uint32_t) m, 0xabcdef};

	memcpy(dst, h, 8);
	memcpy(dst + 8, xy, 16 * m);
	memcpy(dst + 8 + 16 * m, xy, 16);
}

/*
 * The diagram written by tdc_voronoi_emit on "threads" threads; NULL (and a
 * failed CHECK) on error.
 */
static char *
emit_diagram(const char *name, const tdc_job *job, const double env[4], int threads,
			 size_t *bytes, size_t *cells)
{
	tdc_cell_writer w = {test_cell_size, test_cell_write, NULL};
	tdc_voronoi *v = NULL;
	char		err[256] = "";
	char	   *out = NULL;
	int			rc;

	rc = tdc_voronoi_start_emit(job, env, threads, &w, &v, err, sizeof(err));
	if (rc == TDC_OK && (rc = tdc_voronoi_wait(v, -1)) == TDC_OK)
	{
		*bytes = tdc_voronoi_emit_size(v, cells);
		/* poisoned: every byte must be written */
		out = malloc(*bytes + 1);
		memset(out, 0x5a, *bytes + 1);
		rc = tdc_voronoi_emit(v, out, err, sizeof(err));
		if (rc == TDC_OK)
			rc = tdc_voronoi_wait(v, -1);
	}
	if (rc != TDC_OK && v && !err[0])
		snprintf(err, sizeof(err), "%s", tdc_voronoi_error(v));
	CHECK(rc == TDC_OK, "%s: emit on %d threads: %s", name, threads, err);
	CHECK(out == NULL || (unsigned char) out[*bytes] == 0x5a,
		  "%s: emit on %d threads wrote past the end", name, threads);
	tdc_voronoi_free(v);
	if (rc != TDC_OK)
	{
		free(out);
		return NULL;
	}
	return out;
}

/*
 * tdc_voronoi_emit against the cells of tdc_voronoi_cell (v): the same
 * rings, one per site, in the input order of each site's first point, and
 * the same bytes on 1, 2 and 3 threads.
 */
static void
check_emit(const char *name, const tdc_job *job, const tdc_voronoi *v, const double env[4])
{
	size_t		nin = tdc_num_input(job),
				lim = tdc_site_id_limit(job),
				bytes = 0,
				cells = 0,
				expect_bytes = 0,
				expect_cells = 0;
	unsigned char *seen = calloc(lim + 1, 1);
	char	   *expect,
			   *p,
			   *got[3] = {NULL, NULL, NULL};
	long		bad_threads = 0;

	for (size_t i = 0; i < nin; i++)
	{
		const double *c;
		uint32_t	s = tdc_input_site(job, i);
		size_t		m = tdc_voronoi_cell(v, s, &c);

		if (!seen[s] && m > 0)
		{
			expect_bytes += test_cell_size(NULL, m);
			expect_cells++;
		}
		seen[s] = 1;
	}
	expect = malloc(expect_bytes + 1);
	p = expect;
	memset(seen, 0, lim + 1);
	for (size_t i = 0; i < nin; i++)
	{
		const double *c;
		uint32_t	s = tdc_input_site(job, i);
		size_t		m = tdc_voronoi_cell(v, s, &c);

		if (!seen[s] && m > 0)
		{
			test_cell_write(NULL, p, c, m);
			p += test_cell_size(NULL, m);
		}
		seen[s] = 1;
	}
	for (int t = 0; t < 3; t++)
	{
		size_t		b = 0,
					k = 0;

		got[t] = emit_diagram(name, job, env, t + 1, &b, &k);
		if (got[t] == NULL)
			goto done;
		if (t == 0)
		{
			bytes = b;
			cells = k;
		}
		else if (b != bytes || k != cells || memcmp(got[0], got[t], bytes) != 0)
			bad_threads++;
	}
	CHECK(bytes == expect_bytes && cells == expect_cells &&
		  memcmp(got[0], expect, bytes) == 0,
		  "%s: emitted cells (%zu bytes, %zu cells) differ from the cells in input order "
		  "(%zu bytes, %zu cells)", name, bytes, cells, expect_bytes, expect_cells);
	CHECK(bad_threads == 0, "%s: emitted bytes differ between 1, 2 and 3 threads", name);
done:
	for (int t = 0; t < 3; t++)
		free(got[t]);
	free(expect);
	free(seen);
}

/*
 * All checks of one diagram; returns the number of failed checks (each also
 * reported through CHECK once per kind).
 */
static void
check_diagram(const char *name, const double *xy, size_t n, const double *env_in,
			  int threads, double area_tol)
{
	tdc_job    *job = NULL;
	tdc_voronoi *v = NULL,
			   *v1 = NULL;
	tdc_options opt;
	char		err[256];
	double		env[4];
	int			rc;
	size_t		nsites = 0,
				ncells = 0,
				nedges = 0,
				cap = 0;
	long		collapsed = 0,
				bad_ring = 0,
				bad_convex = 0,
				bad_contain = 0,
				bad_env = 0,
				bad_share = 0,
				bad_same = 0;
	double		area = 0,
				env_area;
	dedge	   *edges = NULL;

	tdc_options_init(&opt);
	opt.threads = threads;
	opt.tolerance = vor_tolerance;
	rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "%s: triangulate: %s", name, err);
	if (rc != TDC_OK)
	{
		tdc_job_free(job);
		return;
	}
	if (env_in)
		memcpy(env, env_in, sizeof(env));
	else
		tdc_voronoi_default_env(job, env);
	env_area = (env[2] - env[0]) * (env[3] - env[1]);
	rc = tdc_voronoi_build(job, env, threads, &v, err, sizeof(err));
	CHECK(rc == TDC_OK, "%s: voronoi: %s", name, err);
	if (rc != TDC_OK)
		goto done;
	if (threads != 1)
	{
		rc = tdc_voronoi_build(job, env, 1, &v1, err, sizeof(err));
		CHECK(rc == TDC_OK, "%s: voronoi 1 thread: %s", name, err);
	}

	for (uint32_t s = 0; s < tdc_site_id_limit(job); s++)
	{
		const double *c,
				   *site;
		size_t		m = tdc_voronoi_cell(v, s, &c),
					first_edge = nedges;
		double		a = 0,
					turn = 0;

		if (v1 && s < tdc_site_id_limit(job))
		{
			const double *c1;
			size_t		m1 = tdc_voronoi_cell(v1, s, &c1);

			if (m1 != m || (m && memcmp(c, c1, m * 2 * sizeof(double)) != 0))
				bad_same++;
		}
		if (m == 0)
			continue;
		ncells++;
		site = tdc_site_xy(job, s);
		if (m < 3 && !vor_near_degenerate)
		{
			bad_ring++;
			continue;
		}

		for (size_t i = 0; i < m; i++)
		{
			const double *p = c + 2 * i,
					   *q = c + 2 * ((i + 1) % m),
					   *r = c + 2 * ((i + 2) % m);
			double		ax = q[0] - p[0],
						ay = q[1] - p[1],
						bx = r[0] - q[0],
						by = r[1] - q[1];

			if (p[0] == q[0] && p[1] == q[1])
				bad_ring++;
			if (tdc_orient2d(p, q, r) < 0 && !vor_near_degenerate)
				bad_convex++;
			if (tdc_orient2d(p, q, site) < 0 && !vor_near_degenerate)
				bad_contain++;
			if (p[0] < env[0] || p[0] > env[2] || p[1] < env[1] || p[1] > env[3])
				bad_env++;
			turn += atan2(ax * by - ay * bx, ax * bx + ay * by);
			/* shoelace about the site: small terms, little cancellation */
			a += (p[0] - site[0]) * (q[1] - site[1]) - (q[0] - site[0]) * (p[1] - site[1]);
			if (!on_env_side(env, p, q))
			{
				if (nedges == cap)
				{
					cap = cap ? 2 * cap : 1024;
					edges = realloc(edges, cap * sizeof(dedge));
				}
				memcpy(edges[nedges].p, p, sizeof(double) * 2);
				memcpy(edges[nedges].q, q, sizeof(double) * 2);
				edges[nedges].sliver = false;
				nedges++;
			}
		}
		if (vor_near_degenerate && !near_ring(c, m, site, 1e-12 * (env[2] - env[0])))
		{
			if (getenv("VOR_VERBOSE"))
			{
				fprintf(stderr, "%s: site %u (%.17g %.17g) outside, ring:\n", name, s, site[0], site[1]);
				for (size_t k = 0; k < m; k++)
					fprintf(stderr, "   %.17g %.17g\n", c[2 * k], c[2 * k + 1]);
			}
			bad_contain++;
		}
		if (fabs(turn - 2 * M_PI) > 1e-6 || m < 3)
		{
			if (vor_near_degenerate)
			{
				collapsed++;
				for (size_t k = first_edge; k < nedges; k++)
					edges[k].sliver = true;
			}
			else
				bad_convex++;
		}
		area += a / 2;
	}
	nsites = tdc_num_sites(job);
	if (nedges > 0)
		qsort(edges, nedges, sizeof(dedge), cmp_dedge);
	for (size_t i = 0; i < nedges; i++)
	{
		dedge		r;

		memcpy(r.p, edges[i].q, sizeof(r.p));
		memcpy(r.q, edges[i].p, sizeof(r.q));
		/*
		 * Exactly one reversed copy, and the edge itself only once; a
		 * sliver's edges (near-degenerate mode) may pair up inside it.
		 */
		if (edges[i].sliver)
			continue;
		if (!bsearch(&r, edges, nedges, sizeof(dedge), cmp_dedge) ||
			(i + 1 < nedges && cmp_dedge(&edges[i], &edges[i + 1]) == 0 &&
			 !edges[i + 1].sliver) ||
			(i > 0 && cmp_dedge(&edges[i], &edges[i - 1]) == 0 && !edges[i - 1].sliver))
			bad_share++;
	}
	check_emit(name, job, v, env);
	if (collapsed)
		printf("voronoi: %s: %ld cells collapsed to slivers by rounding\n", name, collapsed);
	CHECK(ncells == nsites, "%s: %zu cells for %zu sites", name, ncells, nsites);
	CHECK(bad_ring == 0, "%s: %ld rings too short or with repeated vertices", name, bad_ring);
	CHECK(bad_convex == 0, "%s: %ld non-convex turns or windings", name, bad_convex);
	CHECK(bad_contain == 0, "%s: %ld cells not containing their site", name, bad_contain);
	CHECK(bad_env == 0, "%s: %ld vertices outside the envelope", name, bad_env);
	CHECK(bad_share == 0, "%s: %ld of %zu inner edges not shared bit-identically", name,
		  bad_share, nedges);
	CHECK(bad_same == 0, "%s: %ld cells differ between 1 and %d threads", name, bad_same, threads);
	CHECK(fabs(area - env_area) <= area_tol * env_area,
		  "%s: cell areas %.17g, envelope %.17g, relative error %.3g", name, area, env_area,
		  fabs(area - env_area) / env_area);
done:
	free(edges);
	tdc_voronoi_free(v);
	tdc_voronoi_free(v1);
	tdc_job_free(job);
}

static double *
gen_uniform(size_t n, double scale, double off)
{
	double	   *xy = malloc(2 * n * sizeof(double));

	for (size_t i = 0; i < 2 * n; i++)
		xy[i] = off + scale * vurand();
	return xy;
}

static double *
gen_clustered(size_t n)
{
	double	   *xy = malloc(2 * n * sizeof(double));

	for (size_t i = 0; i < n; i++)
	{
		double		cx = (double) (vrng() % 10),
					cy = (double) (vrng() % 10);

		xy[2 * i] = cx + 0.01 * vurand() * vurand();
		xy[2 * i + 1] = cy + 0.01 * vurand() * vurand();
	}
	return xy;
}

static double *
gen_lattice(size_t side)
{
	double	   *xy = malloc(2 * side * side * sizeof(double));

	for (size_t i = 0; i < side * side; i++)
	{
		xy[2 * i] = (double) (i % side);
		xy[2 * i + 1] = (double) (i / side);
	}
	return xy;
}

void
test_voronoi(void)
{
	size_t		big = tdc_test_quick ? 30000 : 60000;
	double	   *xy;

	test_circumcenters();
	test_circumcenter_rounding();
	vrng_state = 42;

	xy = gen_uniform(2000, 1, 0);
	check_diagram("uniform 2000", xy, 2000, NULL, 1, 1e-12);
	free(xy);
	xy = gen_uniform(big, 1000, -500);
	check_diagram("uniform threaded", xy, big, NULL, 2, 1e-12);
	free(xy);
	xy = gen_clustered(big);
	check_diagram("clustered threaded", xy, big, NULL, 2, 1e-12);
	free(xy);
	{
		/* duplicates of earlier and later points, threaded; then a tolerance */
		xy = gen_uniform(big, 1000, -500);
		for (size_t i = 0; i < big; i += 3)
		{
			size_t		j = vrng() % big;

			xy[2 * i] = xy[2 * j];
			xy[2 * i + 1] = xy[2 * j + 1];
		}
		check_diagram("duplicates threaded", xy, big, NULL, 2, 1e-12);
		vor_tolerance = 2.0;
		check_diagram("tolerance threaded", xy, big, NULL, 2, 1e-12);
		vor_tolerance = 0;
		free(xy);
	}
	xy = gen_lattice(60);
	check_diagram("lattice 60x60", xy, 3600, NULL, 1, 1e-12);
	free(xy);
	xy = gen_lattice(180);
	check_diagram("lattice 180x180 threaded", xy, 180 * 180, NULL, 2, 1e-12);
	{
		/* the lattice clipped at its own box: every hull site on the border */
		double		env[4] = {0, 0, 179, 179};

		check_diagram("lattice on envelope border", xy, 180 * 180, env, 2, 1e-12);
	}
	free(xy);
	{
		double		line[2 * 50],
					diag[2 * 50];

		for (int i = 0; i < 50; i++)
		{
			line[2 * i] = i * i * 0.37;
			line[2 * i + 1] = 5;
			diag[2 * i] = i * 3.0;
			diag[2 * i + 1] = -i * 2.0;
		}
		check_diagram("collinear horizontal", line, 50, NULL, 1, 1e-12);
		check_diagram("collinear diagonal", diag, 50, NULL, 1, 1e-12);
	}
	{
		double		one[2] = {3, 4};
		double		env[4] = {0, 0, 10, 10};
		double		two[4] = {0, 0, 2, 0};
		double		three_line[6] = {0, 0, 2, 0, 5, 0};
		double		three[6] = {0, 0, 2, 0, 0, 1};
		double		dups[12] = {1, 1, 1, 1, 2, 5, 2, 5, 1, 1, 7, 3};

		check_diagram("one site", one, 1, env, 1, 1e-15);
		check_diagram("two sites", two, 2, NULL, 1, 1e-15);
		check_diagram("three collinear", three_line, 3, NULL, 1, 1e-15);
		check_diagram("three", three, 3, NULL, 1, 1e-15);
		check_diagram("duplicates", dups, 6, NULL, 1, 1e-15);
	}
	{
		/* PostGIS's collinear result: slabs x < 1, 1 < x < 3.5, x > 3.5 in [-5, 10] x [-5, 5] */
		double		three_line[6] = {0, 0, 2, 0, 5, 0};
		tdc_job    *job;
		tdc_voronoi *v;
		double		env[4];
		char		err[256];
		const double *c;
		size_t		m;
		bool		ok = true;

		tdc_triangulate(three_line, 3, NULL, &job, err, sizeof(err));
		tdc_voronoi_default_env(job, env);
		CHECK(env[0] == -5 && env[1] == -5 && env[2] == 10 && env[3] == 5,
			  "default envelope %g %g %g %g", env[0], env[1], env[2], env[3]);
		tdc_voronoi_build(job, env, 1, &v, err, sizeof(err));
		m = tdc_voronoi_cell(v, tdc_input_site(job, 1), &c);
		for (size_t i = 0; i < m; i++)
			ok = ok && (c[2 * i] == 1 || c[2 * i] == 3.5) && fabs(c[2 * i + 1]) == 5;
		CHECK(m == 4 && ok, "middle slab of 3 collinear sites: %zu vertices", m);
		tdc_voronoi_free(v);
		tdc_job_free(job);
	}
	{
		double	   *tiny = gen_uniform(3000, 1e-50, 1e-49),
				   *huge = gen_uniform(3000, 1e50, -3e50);

		check_diagram("tiny scale", tiny, 3000, NULL, 1, 1e-12);
		check_diagram("huge scale", huge, 3000, NULL, 1, 1e-12);
		free(tiny);
		free(huge);
	}
	{
		/* sites on the border of an extend_to envelope, and far inside a big one */
		double	   *u = gen_uniform(3000, 1, 0);
		double		env[4] = {-1e6, -3, 2, 1e6};

		u[0] = 0, u[1] = 0;		/* a corner of the sites' box */
		check_diagram("big extend_to envelope", u, 3000, env, 1, 1e-9);
		free(u);
	}
	{
		/*
		 * Lattices nudged by a few ulps (found by fuzz_voronoi): near
		 * duplicates on the hull make hair-thin cells, nearly collinear hull
		 * sites put Voronoi vertices 1e17 away and with them the box the
		 * rays are cut to.  A crossing interpolated from that far end lost
		 * 0.09 in y and left a site outside its cell.
		 */
		double	   *nudged = malloc(2 * 400 * sizeof(double));

		vor_near_degenerate = true;
		for (int seed = 0; seed < 40; seed++)
		{
			char		name[64];

			vrng_state = 1000 + seed;
			for (int i = 0; i < 400; i++)
			{
				uint64_t	r = vrng();
				double		x = 1 + (r & 15),
							y = 1 + ((r >> 4) & 15);

				for (int k = 0; k < (int) ((r >> 8) & 3); k++)
					x = nextafter(x, (r >> 10) & 1 ? INFINITY : -INFINITY);
				for (int k = 0; k < (int) ((r >> 11) & 3); k++)
					y = nextafter(y, (r >> 13) & 1 ? INFINITY : -INFINITY);
				nudged[2 * i] = x;
				nudged[2 * i + 1] = y;
			}
			snprintf(name, sizeof(name), "nudged lattice %d", seed);
			check_diagram(name, nudged, 400, NULL, 1, 1e-9);
		}
		vor_near_degenerate = false;
		free(nudged);
	}
	{
		/*
		 * Four sites almost on the diagonal (found by fuzz_voronoi): the two
		 * flat triangles have circumcenters about 1e16 away, rounded at that
		 * scale, and the cell edges between them cross the envelope near
		 * the sites.  Interpolated from those end points, the cell of
		 * (1, 1) was cut along x + y = -6 instead of its bisector x + y = 3
		 * with (2, 2), missing its site; a crossing now comes from the
		 * bisector of the two sites.
		 */
		double		flat[8] = {0x1.e000000000003p+3, 0x1.e000000000003p+3,
							   0x1.fffffffffffffp+0, 0x1.ffffffffffffep+0,
							   0x1.0000000000003p+0, 0x1.0000000000003p+0,
							   0x1.0000000000003p+4, 0x1.0000000000003p+4};

		check_diagram("nearly collinear hull", flat, 4, NULL, 1, 1e-12);
	}
	{
		/*
		 * hull cell wound twice: five sites on the diagonal up to ulps
		 * (fuzz/known/voronoi_flat_hull_double_wound).  The cell of
		 * (2, 2) is a strip 10 wide between two Voronoi vertices 1e17 out;
		 * its two rays leave B (as large) 10 apart, rounded at B's scale
		 * their exits swapped, and closing from one to the other went round
		 * all of B: the ring wound twice, the areas summed to twice E.  The
		 * corners of B in a cell are now decided exactly.
		 */
		double		flat[10] = {0x1.e000000000003p+3, 0x1.e000000000003p+3,
								0x1.fffffffffffffp+0, 0x1.ffffffffffffep+0,
								0x1p+0, 0x1.fffffffffffffp-1,
								0x1.fffffffffffffp+3, 0x1.ffffffffffffep+3,
								0x1.0000000000003p+4, 0x1.0000000000003p+4};

		check_diagram("hull cell wound twice", flat, 5, NULL, 1, 1e-12);
	}
	{
		/*
		 * circumcenter NaN: two sites 4.5e-37 apart under one at 1.6e40
		 * (fuzz/known/voronoi_box_exit_side).  The triangle is 2^-250 thin,
		 * double-double lost D entirely, divided by 0, and the cells of the
		 * far site and of (0, -4.5e-37) came out empty.
		 */
		double		tiny_edge[6] = {-0x1.fd09c81cdb4a1p+68, 0x1.809d0f96c6b79p+133,
									0, 0, 0, -0x1.3169a28p-121};

		check_diagram("circumcenter NaN", tiny_edge, 3, NULL, 1, 1e-12);
	}
	{
		/*
		 * thin strips rounded at a far vertex's scale: four sites on x = 0
		 * (y = -4.5e-37, 0, 0.107, 139264) under one at 1.6e40 (found by
		 * fuzz_voronoi).  The cells are horizontal strips; their corners
		 * are circumcenters at x = -2.3e59, whose y was right only to
		 * 2^-98 of 2.3e59 (2e7 off, not 0.054), so the strip of 0.107 was
		 * wound backwards over [0, 2e7] and an edge was in three cells.
		 * Each coordinate is now right to its own ulp.
		 */
		double		strips[10] = {-0x1.fd09c81cdb4a1p+68, 0x1.809d0f96c6b79p+133,
								  0, 0, 0, -0x1.3169a28p-121, 0, 0x1.1p+17,
								  0, 0x1.b8ap-4};

		check_diagram("thin strips under a far site", strips, 5, NULL, 1, 1e-12);
	}
	{
		/*
		 * A hull edge between two sites 3.6e-37 apart, under a site at
		 * 1.7e40: its ray's direction is so small against the box that the
		 * exit time overflows, and box_exit took side -1, read before a
		 * table (found by fuzz_voronoi under UBSan; check-core-asan fails
		 * here without the fix).
		 */
		double		tiny_edge[6] = {-0x1.fd09c81cdb4a1p+68, 0x1.809d0f96c6b79p+133,
									0, 0, 0, -0x1.3169a28p-121};
		tdc_job    *job;
		tdc_voronoi *v = NULL;
		double		env[4];
		char		err[256];
		int			rc,
					outside = 0;

		tdc_triangulate(tiny_edge, 3, NULL, &job, err, sizeof(err));
		tdc_voronoi_default_env(job, env);
		rc = tdc_voronoi_build(job, env, 1, &v, err, sizeof(err));
		for (uint32_t s = 0; rc == TDC_OK && s < tdc_site_id_limit(job); s++)
		{
			const double *c;
			size_t		m = tdc_voronoi_cell(v, s, &c);

			for (size_t i = 0; i < m; i++)
				if (!(c[2 * i] >= env[0] && c[2 * i] <= env[2] &&
					  c[2 * i + 1] >= env[1] && c[2 * i + 1] <= env[3]))
					outside++;
		}
		CHECK(rc == TDC_OK && outside == 0, "tiny hull edge: rc %d, %d vertices outside", rc, outside);
		tdc_voronoi_free(v);
		tdc_job_free(job);
	}
	{
		/* bad envelopes are refused */
		double		pts[6] = {0, 0, 2, 0, 0, 1};
		double		env[4] = {0.5, 0, 3, 3};
		tdc_job    *job;
		tdc_voronoi *v = NULL;
		char		err[256];
		int			rc;

		tdc_triangulate(pts, 3, NULL, &job, err, sizeof(err));
		rc = tdc_voronoi_build(job, env, 1, &v, err, sizeof(err));
		CHECK(rc == TDC_EINVAL && v == NULL, "an envelope not containing the sites: rc %d", rc);
		tdc_job_free(job);
	}
}
