/*
 * fuzz_voronoi.c
 *		libFuzzer target for the Voronoi cells of the core (voronoi.c).
 *
 * Input layout (missing bytes read as 0):
 *
 *	byte 0		mode (% 6): how the remaining bytes become points
 *				0 small integers 0..15 (lattices: cocircular, collinear, duplicates)
 *				1 int16 pairs scaled by 2^(byte 2 % 64 - 32)
 *				2 collinear: one byte per point along a small integer direction
 *				3 near-degenerate: integers 1..16 nudged by a few ulps
 *				4 cocircular: lattice points of x^2 + y^2 = 5525
 *				5 raw doubles, kept only when finite and within the core's range
 *	byte 1		bits 0-1: threads - 1; bit 2: extend the envelope (bytes 3-4)
 *	byte 2		scale (mode 1)
 *	bytes 3-4	extend_to offsets: the envelope grows by these multiples of its size
 *	bytes 5..	data
 *
 * Every site must have a cell; every cell must have no repeated consecutive
 * vertex, lie inside the envelope and contain its site, or pass within
 * 1e-12 of the envelope's size plus 2^-49 of its largest coordinate (a few
 * ulps: the vertices are rounded doubles) of it.  Nothing is excused for
 * near-duplicate or nearly collinear sites any more: far Voronoi vertices
 * (fuzz/known/voronoi_flat_hull_double_wound) and 2^-250-thin triangles
 * (voronoi_box_exit_side) were root causes fixed in voronoi.c.  What stays
 * is what doubles cannot represent: a cell narrower than their spacing
 * (sites an ulp apart, mode 3) may turn right by an ulp, grow an ulp-long
 * spike (A, B, A: fuzz/known/voronoi_edge_not_shared) or collapse to a
 * zero-area sliver (a ring of 1 or 2, winding 0 or -1, never more than
 * once either way); such a cell still must
 * pass within that slack of its site, only its edges are left out of the
 * sharing check (the core suite counts them on its nudged lattices).  Every
 * other edge not on the envelope's border must appear reversed, bit for
 * bit, in exactly one other cell; the areas must add up to the envelope's
 * within 1e-9 (relative); the cells must not depend on the thread count.
 * Anything else aborts.  FUZZ_VERBOSE=1 prints each input's points (%a).
 */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tdc.h"
#include "engine/predicates.h"

#define MAX_POINTS		3000

static void die(const char *fmt,...) __attribute__((format(printf, 1, 2), noreturn));

static void
die(const char *fmt,...)
{
	va_list		ap;

	fprintf(stderr, "fuzz_voronoi: ");
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fprintf(stderr, "\n");
	abort();
}

typedef struct edge
{
	double		p[2],
				q[2];
	bool		sliver;
} edge;

static int
cmp_edge(const void *a, const void *b)
{
	return memcmp(a, b, 4 * sizeof(double));
}

static bool
on_side(const double *e, const double *p, const double *q)
{
	return (p[0] == e[0] && q[0] == e[0]) || (p[0] == e[2] && q[0] == e[2]) ||
		(p[1] == e[1] && q[1] == e[1]) || (p[1] == e[3] && q[1] == e[3]);
}

/* q inside the ring (crossing count) or within tol of its boundary */
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

		if ((a[1] > q[1]) != (b[1] > q[1]) && q[0] < a[0] + (q[1] - a[1]) * dx / dy)
			in = !in;
		t = fmin(fmax(t, 0), 1);
		best = fmin(best, hypot(q[0] - (a[0] + t * dx), q[1] - (a[1] + t * dy)));
	}
	return in || best <= tol;
}

/* tdc_voronoi_emit's layout here: the count, then the ring */
static size_t
emit_size(void *arg, size_t m)
{
	return 8 + 16 * m;
}

static void
emit_write(void *arg, char *dst, const double *xy, size_t m)
{
	uint64_t	n = m;

	memcpy(dst, &n, 8);
	memcpy(dst + 8, xy, 16 * m);
}

/*
 * The cells written by tdc_voronoi_emit are the cells of v (built the other
 * way), one per site in the input order of its first point.
 */
static void
check_emit(const tdc_job *job, const tdc_voronoi *v, const double *env, int threads)
{
	tdc_cell_writer w = {emit_size, emit_write, NULL};
	tdc_voronoi *e = NULL;
	char		err[256];
	size_t		cells,
				bytes,
				off = 0,
				lim = tdc_site_id_limit(job);
	char	   *out;
	unsigned char *seen = calloc(lim + 1, 1);

	if (tdc_voronoi_start_emit(job, env, threads, &w, &e, err, sizeof(err)) != TDC_OK ||
		tdc_voronoi_wait(e, -1) != TDC_OK)
		die("voronoi emit (sizing) failed: %s", e ? tdc_voronoi_error(e) : err);
	bytes = tdc_voronoi_emit_size(e, &cells);
	out = malloc(bytes + 1);
	if (tdc_voronoi_emit(e, out, err, sizeof(err)) != TDC_OK || tdc_voronoi_wait(e, -1) != TDC_OK)
		die("voronoi emit (writing) failed: %s", tdc_voronoi_error(e));
	for (size_t i = 0; i < tdc_num_input(job); i++)
	{
		uint32_t	s = tdc_input_site(job, i);
		const double *c;
		size_t		m = tdc_voronoi_cell(v, s, &c);
		uint64_t	n;

		if (seen[s] || m == 0)
			continue;
		seen[s] = 1;
		memcpy(&n, out + off, 8);
		if (off + 8 + 16 * m > bytes || n != m || memcmp(out + off + 8, c, 16 * m) != 0)
			die("emitted cell of site %u differs", s);
		off += 8 + 16 * m;
		cells--;
	}
	if (off != bytes || cells != 0)
		die("emitted cells: not one per site");
	free(out);
	free(seen);
	tdc_voronoi_free(e);
}

static void
check(const tdc_job *job, const tdc_voronoi *v, const tdc_voronoi *v1, const double *env)
{
	/*
	 * Containment slack: 1e-12 of the envelope, plus a few ulps of its
	 * largest coordinate, the spacing of the doubles a vertex is rounded
	 * to (an envelope only ulps wide is all ulps).
	 */
	double		big = fmax(fmax(fabs(env[0]), fabs(env[1])), fmax(fabs(env[2]), fabs(env[3])));
	size_t		cap = 64,
				ne = 0;
	edge	   *edges = malloc(cap * sizeof(edge));
	double		area = 0,
				envarea = (env[2] - env[0]) * (env[3] - env[1]),
				tol = 1e-12 * fmax(env[2] - env[0], env[3] - env[1]) + 0x1p-49 * big;
	size_t		ncells = 0;

	for (uint32_t s = 0; s < tdc_site_id_limit(job); s++)
	{
		const double *c,
				   *c1,
				   *site = tdc_site_xy(job, s);
		size_t		m = tdc_voronoi_cell(v, s, &c),
					m1 = tdc_voronoi_cell(v1, s, &c1),
					first = ne;
		double		turn = 0,
					a = 0;
		bool		convex = true,
					spike = false;

		if (m != m1 || (m && memcmp(c, c1, m * 16) != 0))
			die("site %u: cells differ between thread counts", s);
		if (m == 0)
			continue;
		ncells++;
		for (size_t i = 0; i < m; i++)
		{
			const double *p = c + 2 * i,
					   *q = c + 2 * ((i + 1) % m),
					   *r = c + 2 * ((i + 2) % m);

			/* (a ring of 1 vertex is a collapsed sliver, below) */
			if (m > 1 && p[0] == q[0] && p[1] == q[1])
				die("site %u: repeated vertex", s);
			if (p[0] < env[0] || p[0] > env[2] || p[1] < env[1] || p[1] > env[3])
				die("site %u: vertex outside the envelope", s);
			if (tdc_orient2d(p, q, r) < 0)
				convex = false;
			turn += atan2((q[0] - p[0]) * (r[1] - q[1]) - (q[1] - p[1]) * (r[0] - q[0]),
						  (q[0] - p[0]) * (r[0] - q[0]) + (q[1] - p[1]) * (r[1] - q[1]));
			a += (p[0] - site[0]) * (q[1] - site[1]) - (q[0] - site[0]) * (p[1] - site[1]);
			if (!on_side(env, p, q))
			{
				if (ne == cap)
					edges = realloc(edges, (cap *= 2) * sizeof(edge));
				memcpy(edges[ne].p, p, 16);
				memcpy(edges[ne].q, q, 16);
				edges[ne].sliver = false;
				ne++;
			}
		}
		for (size_t i = 0; i < m && m >= 3; i++)
			if (c[2 * i] == c[2 * ((i + 2) % m)] && c[2 * i + 1] == c[2 * ((i + 2) % m) + 1])
				spike = true;	/* A, B, A: an ulp-wide part, known below */
		if (fabs(turn) > 2 * M_PI + 1e-6)
			die("site %u: cell wound %.3g times", s, turn / (2 * M_PI));
		if (m < 3 || spike || fabs(turn - 2 * M_PI) > 1e-6)
		{
			/* collapsed by rounding: only near-duplicate sites make these */
			for (size_t k = first; k < ne; k++)
				edges[k].sliver = true;
		}
		else if (convex)
		{
			for (size_t i = 0; i < m; i++)
				if (tdc_orient2d(c + 2 * i, c + 2 * ((i + 1) % m), site) < 0 &&
					!near_ring(c, m, site, tol))
					die("site %u: outside its convex cell", s);
		}
		if (!near_ring(c, m, site, tol))
			die("site %u: outside its cell by more than %g", s, tol);
		area += a / 2;
	}
	if (ncells != tdc_num_sites(job))
		die("%zu cells for %zu sites", ncells, tdc_num_sites(job));
	qsort(edges, ne, sizeof(edge), cmp_edge);
	for (size_t i = 0; i < ne; i++)
	{
		edge		r;

		if (edges[i].sliver)
			continue;
		memcpy(r.p, edges[i].q, 16);
		memcpy(r.q, edges[i].p, 16);
		if (!bsearch(&r, edges, ne, sizeof(edge), cmp_edge) ||
			(i + 1 < ne && cmp_edge(&edges[i], &edges[i + 1]) == 0 && !edges[i + 1].sliver) ||
			(i > 0 && cmp_edge(&edges[i], &edges[i - 1]) == 0 && !edges[i - 1].sliver))
			die("edge %zu of %zu not shared exactly once", i, ne);
	}
	free(edges);
	if (!(fabs(area - envarea) <= 1e-9 * envarea))
		die("cell areas %.17g, envelope %.17g", area, envarea);
}

static double circle_pts[256][2];
static int	ncircle;

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	uint8_t		hdr[5] = {0};
	double	   *xy;
	size_t		n = 0;
	int			mode,
				threads;
	tdc_options opt;
	tdc_job    *job = NULL;
	tdc_voronoi *v = NULL,
			   *v1 = NULL;
	double		env[4];
	char		err[256];

	if (ncircle == 0)
		for (int x = -75; x <= 75; x++)
			for (int y = -75; y <= 75; y++)
				if (x * x + y * y == 5525 && ncircle < 256)
				{
					circle_pts[ncircle][0] = x;
					circle_pts[ncircle][1] = y;
					ncircle++;
				}
	memcpy(hdr, data, size < 5 ? size : 5);
	data += size < 5 ? size : 5;
	size -= size < 5 ? size : 5;
	mode = hdr[0] % 6;
	threads = (hdr[1] & 3) + 1;
	xy = malloc(2 * MAX_POINTS * sizeof(double) + 16);
	switch (mode)
	{
		case 0:
			for (size_t i = 0; i < size && n < MAX_POINTS; i++, n++)
				xy[2 * n] = data[i] & 15, xy[2 * n + 1] = data[i] >> 4;
			break;
		case 1:
			for (size_t i = 0; i + 4 <= size && n < MAX_POINTS; i += 4, n++)
			{
				int16_t		a,
							b;

				memcpy(&a, data + i, 2);
				memcpy(&b, data + i + 2, 2);
				xy[2 * n] = ldexp(a, hdr[2] % 64 - 32);
				xy[2 * n + 1] = ldexp(b, hdr[2] % 64 - 32);
			}
			break;
		case 2:
			for (size_t i = 0; i < size && n < MAX_POINTS; i++, n++)
				xy[2 * n] = data[i] * (1 + (hdr[2] & 7)), xy[2 * n + 1] = data[i] * ((hdr[2] >> 3) & 7);
			break;
		case 3:
			for (size_t i = 0; i + 1 < size && n < MAX_POINTS; i += 2, n++)
			{
				/* from 1: nudging 0 would make subnormals, outside the core's range */
				double		x = 1 + (data[i] & 15),
							y = 1 + (data[i] >> 4);

				for (int k = 0; k < (data[i + 1] & 3); k++)
					x = nextafter(x, (data[i + 1] & 4) ? INFINITY : -INFINITY);
				for (int k = 0; k < ((data[i + 1] >> 3) & 3); k++)
					y = nextafter(y, (data[i + 1] & 32) ? INFINITY : -INFINITY);
				xy[2 * n] = x, xy[2 * n + 1] = y;
			}
			break;
		case 4:
			for (size_t i = 0; i < size && n < MAX_POINTS; i++, n++)
				xy[2 * n] = circle_pts[data[i] % ncircle][0], xy[2 * n + 1] = circle_pts[data[i] % ncircle][1];
			break;
		default:
			for (size_t i = 0; i + 16 <= size && n < MAX_POINTS; i += 16)
			{
				double		p[2];

				memcpy(p, data + i, 16);
				if (!isfinite(p[0]) || !isfinite(p[1]) ||
					(p[0] != 0 && (fabs(p[0]) < 1e-60 || fabs(p[0]) > 1e59)) ||
					(p[1] != 0 && (fabs(p[1]) < 1e-60 || fabs(p[1]) > 1e59)))
					continue;
				xy[2 * n] = p[0], xy[2 * n + 1] = p[1];
				n++;
			}
			break;
	}

	if (getenv("FUZZ_VERBOSE"))
		for (size_t i = 0; i < n; i++)
			fprintf(stderr, "%a, %a,\n", xy[2 * i], xy[2 * i + 1]);
	tdc_options_init(&opt);
	opt.threads = threads;
	if (tdc_triangulate(xy, n, &opt, &job, err, sizeof(err)) != TDC_OK)
	{
		/* only coordinates out of the core's range may fail (mode 5 filters them) */
		die("triangulation failed: %s", err);
	}
	if (tdc_num_sites(job) >= 2)
	{
		tdc_voronoi_default_env(job, env);
		if (hdr[1] & 4)
		{
			double		w = env[2] - env[0],
						h = env[3] - env[1];

			env[0] -= w * (hdr[3] & 15);
			env[2] += w * (hdr[3] >> 4);
			env[1] -= h * (hdr[4] & 15);
			env[3] += h * (hdr[4] >> 4);
		}
		if (tdc_voronoi_build(job, env, threads, &v, err, sizeof(err)) != TDC_OK)
			die("voronoi failed: %s", err);
		if (tdc_voronoi_build(job, env, 1, &v1, err, sizeof(err)) != TDC_OK)
			die("voronoi (1 thread) failed: %s", err);
		check(job, v, v1, env);
		check_emit(job, v, env, threads);
	}
	tdc_voronoi_free(v);
	tdc_voronoi_free(v1);
	tdc_job_free(job);
	free(xy);
	return 0;
}
