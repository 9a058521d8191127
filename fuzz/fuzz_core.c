/*
 * fuzz_core.c
 *		libFuzzer target for the tdc_delaunay core (src/core).
 *
 * Input layout (all fields optional; missing bytes read as 0):
 *
 *	byte 0		mode: how the remaining bytes become points (see below)
 *	byte 1		bits 0-1: threads - 1 (1..4); bits 2-4: levels (-1..6);
 *				bit 5: also compare with a single-threaded, undivided run;
 *				bit 6: use a deliberately invalid option (expect TDC_EINVAL)
 *	byte 2		grid size (byte % 65: 0..64)
 *	byte 3		tolerance selector (mostly 0)
 *	bytes 4..	coordinates, interpreted by the mode
 *
 * Modes (byte 0 % 9):
 *	0	raw little-endian double pairs: anything, NaN and huge values
 *		included; the harness decides independently whether the input is
 *		acceptable and demands TDC_EINVAL when it is not
 *	1	small integers: each byte gives x,y in 0..15 (duplicate-heavy,
 *		many cocircular and collinear quadruples)
 *	2	collinear: points on a line with a small integer direction, one
 *		byte per point, plus an optional off-line point
 *	3	int16 pairs scaled by a power of two and shifted by a large offset
 *		(exactness at different magnitudes; offset up to 2^40)
 *	4	palette: each byte picks one of 8 points (mostly duplicates)
 *	5	near-degenerate: small integers nudged by a few ulps
 *	6	float32 pairs widened to double (NaN/Inf possible again)
 *	7	cocircular: lattice points of the circle x^2 + y^2 = 5525 (more
 *		than 40 of them), one byte per point, optional centre shift
 *	8	expanded: a seed generates up to 6000 points (a grid with
 *		duplicates, uniform, or clusters), up to 30000 when bit 7 of the
 *		kind byte is set, so that automatic levels (from 20000 points) and
 *		many subsets are reached
 *
 * On TDC_OK the result must pass tdc_validate_job(), the core's exact check
 * of a finished job (site map, counts, triangles through tdc_validate()).
 * The harness adds what that check cannot know or does not look at: the
 * input it was given (point count; without tolerance, the number of unique
 * points and each point's site coordinates) and the edges (count, endpoints,
 * order).  Any failure, unexpected status, or (when byte 1 bit 5 is set) a
 * triangle set that differs from the reference run aborts, which libFuzzer
 * reports as a crash with the input saved.
 */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tdc.h"
#include "../test/splitmix.h"
#include "../test/xy_oracle.h"

#define MAX_RAW_POINTS		4096
#define MAX_EXPANDED		30000

static void die(const char *fmt,...) __attribute__((format(printf, 1, 2), noreturn));

static void
die(const char *fmt,...)
{
	va_list		ap;

	fprintf(stderr, "fuzz_core: ");
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fprintf(stderr, "\n");
	abort();
}

typedef struct Reader
{
	const uint8_t *p;
	size_t		left;
} Reader;

static uint8_t
rd_u8(Reader *r)
{
	uint8_t		v = 0;

	if (r->left > 0)
	{
		v = *r->p++;
		r->left--;
	}
	return v;
}

static void
rd_bytes(Reader *r, void *dst, size_t n)
{
	size_t		k = n < r->left ? n : r->left;

	memset(dst, 0, n);
	memcpy(dst, r->p, k);
	r->p += k;
	r->left -= k;
}

/* Lattice points of the circle x^2 + y^2 = 5525 (= 5^2 * 13 * 17). */
static double circle_pts[256][2];
static int	ncircle;

static void
init_circle(void)
{
	if (ncircle > 0)
		return;
	for (int x = -75; x <= 75; x++)
		for (int y = -75; y <= 75; y++)
			if (x * x + y * y == 5525 && ncircle < 256)
			{
				circle_pts[ncircle][0] = x;
				circle_pts[ncircle][1] = y;
				ncircle++;
			}
}

static uint64_t
mix(uint64_t *s)
{
	return tdc_splitmix64(s);
}

/* Build the point array for a mode; returns the number of points. */
static size_t
make_points(int mode, Reader *r, double **out)
{
	size_t		n = 0;
	double	   *xy;

	switch (mode)
	{
		case 0:
			{
				size_t		np = r->left / 16;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
					rd_bytes(r, xy + 2 * n, 16);
				break;
			}
		case 1:
			{
				size_t		np = r->left;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					uint8_t		b = rd_u8(r);

					xy[2 * n] = b & 15;
					xy[2 * n + 1] = b >> 4;
				}
				break;
			}
		case 2:
			{
				int			dx = (int) (rd_u8(r) % 9) - 4;
				int			dy = (int) (rd_u8(r) % 9) - 4;
				uint8_t		off = rd_u8(r);
				double		ox = (double) (int8_t) rd_u8(r);
				double		oy = (double) (int8_t) rd_u8(r);
				size_t		np = r->left;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 48);
				for (n = 0; n < np; n++)
				{
					double		t = (double) (int8_t) rd_u8(r);

					xy[2 * n] = ox + t * dx;
					xy[2 * n + 1] = oy + t * dy;
				}
				/* one point off the line (or on it when dx = dy = 0) */
				if (off & 1)
				{
					xy[2 * n] = ox + (off >> 1) - 64;
					xy[2 * n + 1] = oy + ((off >> 1) % 7) - 3 + 0.5;
					n++;
				}
				break;
			}
		case 3:
			{
				int			e = (int) (rd_u8(r) % 120) - 60;
				uint8_t		ob = rd_u8(r);
				double		scale = ldexp(1.0, e);
				double		offset = ldexp((double) (ob & 0x7f), (ob >> 7) ? 33 : 0);
				size_t		np = r->left / 4;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					int16_t		c[2];

					rd_bytes(r, c, 4);
					xy[2 * n] = offset + c[0] * scale;
					xy[2 * n + 1] = offset - c[1] * scale;
				}
				break;
			}
		case 4:
			{
				static const double pal[8][2] = {
					{0, 0}, {1, 0}, {0, 1}, {1, 1}, {0.5, 0.5}, {-0.0, 0}, {2, 2}, {1e-60, 1e60}
				};
				size_t		np = r->left;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					uint8_t		b = rd_u8(r) & 7;

					xy[2 * n] = pal[b][0];
					xy[2 * n + 1] = pal[b][1];
				}
				break;
			}
		case 5:
			{
				size_t		np = r->left / 2;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					uint8_t		a = rd_u8(r);
					uint8_t		b = rd_u8(r);
					double		x = (a & 7) + 1000;
					double		y = ((a >> 3) & 7) + 1000;
					int			nx = (int) (b & 7) - 3;
					int			ny = (int) ((b >> 3) & 7) - 3;

					/* nudge by up to 4 ulps either way */
					for (; nx > 0; nx--)
						x = nextafter(x, INFINITY);
					for (; nx < 0; nx++)
						x = nextafter(x, -INFINITY);
					for (; ny > 0; ny--)
						y = nextafter(y, INFINITY);
					for (; ny < 0; ny++)
						y = nextafter(y, -INFINITY);
					xy[2 * n] = x;
					xy[2 * n + 1] = y;
				}
				break;
			}
		case 6:
			{
				size_t		np = r->left / 8;

				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					float		f[2];

					rd_bytes(r, f, 8);
					xy[2 * n] = f[0];
					xy[2 * n + 1] = f[1];
				}
				break;
			}
		case 7:
			{
				double		cx = (double) (int8_t) rd_u8(r) * 0.25;
				double		cy = (double) (int8_t) rd_u8(r) * 0.25;
				size_t		np = r->left;

				init_circle();
				if (np > MAX_RAW_POINTS)
					np = MAX_RAW_POINTS;
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					uint8_t		b = rd_u8(r);

					if (b >= 2 * ncircle)
					{
						/* the centre, now and then */
						xy[2 * n] = cx;
						xy[2 * n + 1] = cy;
					}
					else
					{
						xy[2 * n] = cx + circle_pts[b % ncircle][0] * ((b / ncircle) ? 1e-3 : 1);
						xy[2 * n + 1] = cy + circle_pts[b % ncircle][1] * ((b / ncircle) ? 1e-3 : 1);
					}
				}
				break;
			}
		default:
			{
				uint64_t	seed = 0;
				uint16_t	cnt;
				uint8_t		kind = rd_u8(r);
				size_t		np;

				rd_bytes(r, &cnt, 2);
				rd_bytes(r, &seed, 8);
				/* large inputs are slow under ASan: only with the 0x80 bit */
				np = cnt % ((kind & 0x80) ? MAX_EXPANDED : 6000);
				xy = malloc(16 * np + 16);
				for (n = 0; n < np; n++)
				{
					uint64_t	z = mix(&seed);

					if (kind % 3 == 0)
					{
						/* integer grid with holes and duplicates */
						xy[2 * n] = (double) (z % 173);
						xy[2 * n + 1] = (double) ((z >> 20) % 173);
					}
					else if (kind % 3 == 1)
					{
						/* uniform in a unit square */
						xy[2 * n] = (z >> 11) * 0x1p-53;
						xy[2 * n + 1] = (mix(&seed) >> 11) * 0x1p-53;
					}
					else
					{
						/* tight clusters far apart */
						double		c = (double) ((z >> 56) % 4) * 1e6;

						xy[2 * n] = c + ((z >> 8) & 0xffff) * 1e-3;
						xy[2 * n + 1] = c + ((z >> 24) & 0xffff) * 1e-3;
					}
				}
				/* the rest of the input overrides a few points */
				while (r->left >= 3 && np > 0)
				{
					uint16_t	idx;
					uint8_t		b;

					rd_bytes(r, &idx, 2);
					b = rd_u8(r);
					xy[2 * (idx % np)] = xy[2 * ((idx + b) % np)];
					xy[2 * (idx % np) + 1] = xy[2 * ((idx + b) % np) + 1] + (b & 1);
				}
				break;
			}
	}
	*out = xy;
	return n;
}

static bool
coord_ok(double c)
{
	if (!isfinite(c))
		return false;
	if (c == 0)
		return true;
	c = fabs(c);
	return c >= TDC_COORD_MIN && c <= TDC_COORD_MAX;
}

/* Triangles as three points each, as canonical_triangles() makes them. */
static int
cmp_tri(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	for (int k = 0; k < 3; k++)
	{
		int			c = cmp_xy(p + 2 * k, q + 2 * k);

		if (c != 0)
			return c;
	}
	return 0;
}

/*
 * Check a successful job: tdc_validate_job() for the sites and triangles,
 * then what it cannot know (the input we passed) or does not look at (edges).
 */
static void
check_job(const tdc_job *job, const double *xy, size_t n, const tdc_options *opt)
{
	uint32_t	lim = tdc_site_id_limit(job);
	size_t		nsites = tdc_num_sites(job);
	size_t		ntri = tdc_num_triangles(job);
	size_t		nedges = tdc_num_edges(job);
	size_t		ne = 0;
	unsigned char *reached;
	tdc_iter	it = {0};
	uint32_t	e[2];
	char		err[512];

	/* the validator walks tdc_num_input() points: it must be all of ours */
	if (tdc_num_input(job) != n)
		die("num_input %zu, %zu points given", tdc_num_input(job), n);
	if (tdc_validate_job(job, err, sizeof(err)) != 0)
		die("validator: %s", err);

	/*
	 * The validator takes the kept sites as given.  Without a tolerance they
	 * must be exactly the distinct input points, each point mapped to the
	 * site with its own coordinates.  tdc_validate_job() has checked that
	 * every input maps below lim, so the lookups below are in range.
	 */
	if (opt->tolerance == 0 && nsites != count_unique(xy, n))
		die("%zu sites, but %zu unique input points", nsites, count_unique(xy, n));
	reached = calloc((size_t) lim + 1, 1);
	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);
		const double *sxy = tdc_site_xy(job, s);

		if (opt->tolerance == 0 && (sxy[0] != xy[2 * i] || sxy[1] != xy[2 * i + 1]))
			die("input %zu (%.17g %.17g) maps to site %u at (%.17g %.17g)",
				i, xy[2 * i], xy[2 * i + 1], s, sxy[0], sxy[1]);
		reached[s] = 1;
	}

	/*
	 * Edges.  The triangulation of m sites is a connected plane graph with
	 * t + 1 faces (a path when the sites are collinear), so Euler's formula
	 * fixes the edge count at m + t - 1; t itself has been validated.
	 */
	if (nedges != (nsites > 0 ? nsites + ntri - 1 : 0))
		die("%zu edges reported, Euler wants %zu sites + %zu triangles - 1",
			nedges, nsites, ntri);
	while (tdc_next_edge(job, &it, e))
	{
		if (ne++ == nedges)
			die("more edges iterated than the %zu reported", nedges);
		if (e[0] >= lim || e[1] >= lim || !reached[e[0]] || !reached[e[1]])
			die("edge %u-%u uses a site no input reaches", e[0], e[1]);
		if (cmp_xy(tdc_site_xy(job, e[0]), tdc_site_xy(job, e[1])) >= 0)
			die("edge %u-%u is not in lexicographic order", e[0], e[1]);
	}
	if (ne != nedges)
		die("%zu edges iterated, %zu reported", ne, nedges);
	free(reached);
}

/*
 * The triangle set by coordinates, comparable between runs whose site ids
 * differ: each triangle's vertices sorted, then the triangles sorted.
 * Sorting the vertices drops the orientation, but only validated jobs come
 * here and the validator demands counter-clockwise triangles, so a vertex
 * set stands for exactly one oriented triangle.
 */
static double *
canonical_triangles(const tdc_job *job)
{
	size_t		ntri = tdc_num_triangles(job);
	double	   *c = malloc(48 * (ntri + 1));
	tdc_iter	it = {0};
	uint32_t	v[3];

	/* validated: the iterator yields exactly ntri triangles */
	for (size_t t = 0; t < ntri && tdc_next_triangle(job, &it, v); t++)
	{
		for (int k = 0; k < 3; k++)
			memcpy(c + 6 * t + 2 * k, tdc_site_xy(job, v[k]), 16);
		qsort(c + 6 * t, 3, 16, cmp_xy);
	}
	qsort(c, ntri, 48, cmp_tri);
	return c;
}

int			LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	Reader		r = {data, size};
	int			mode = rd_u8(&r) % 9;
	uint8_t		ob = rd_u8(&r);
	uint8_t		gb = rd_u8(&r);
	uint8_t		tb = rd_u8(&r);
	tdc_options opt;
	double	   *xy;
	size_t		n;
	bool		valid = true;
	bool		compare = (ob & 0x20) != 0;
	bool		bad_option = (ob & 0x40) != 0;
	tdc_job    *job = NULL;
	char		err[512];
	int			rc;

	tdc_options_init(&opt);
	opt.threads = (ob & 3) + 1;
	opt.levels = (int) ((ob >> 2) & 7) - 1;
	opt.grid_size = gb % 65;
	switch (tb % 16)
	{
		case 1:
			opt.tolerance = 1e-9;
			break;
		case 2:
			opt.tolerance = 0.5;
			break;
		case 3:
			opt.tolerance = 1;
			break;
		case 4:
			opt.tolerance = 2.5;
			break;
		case 5:
			opt.tolerance = ldexp((double) (tb >> 4), (int) (tb >> 4) - 8);
			break;
		default:
			opt.tolerance = 0;
			break;
	}
	if (bad_option)
	{
		switch (tb >> 5)
		{
			case 0:
				opt.tolerance = -1;
				break;
			case 1:
				opt.tolerance = NAN;
				break;
			case 2:
				opt.tolerance = INFINITY;
				break;
			case 3:
				opt.threads = -1;
				break;
			case 4:
				opt.levels = -2;
				break;
			case 5:
				opt.levels = 1000;
				break;
			case 6:
				opt.grid_size = -5;
				break;
			default:
				opt.grid_size = 70000;
				break;
		}
	}

	n = make_points(mode, &r, &xy);
	for (size_t i = 0; i < 2 * n && valid; i++)
		valid = coord_ok(xy[i]);

	rc = tdc_triangulate(n > 0 ? xy : NULL, n, &opt, &job, err, sizeof(err));
	if (bad_option || !valid)
	{
		/* n == 0 with a bad option may fail either way; both are errors */
		if (rc != TDC_EINVAL && !(n == 0 && !bad_option && rc == TDC_OK))
			die("invalid input or option not rejected with TDC_EINVAL (status %d, n %zu): %s",
				rc, n, err);
		/* tdc_triangulate keeps the job (with its message) when it failed late */
		if (job != NULL && strcmp(tdc_job_error(job), err) != 0)
			die("job message differs from err: %s / %s", tdc_job_error(job), err);
		tdc_job_free(job);
		free(xy);
		return 0;
	}
	if (rc != TDC_OK)
		die("valid input failed: %s", err);
	check_job(job, xy, n, &opt);

	if (compare)
	{
		/*
		 * The symbolic tie-break makes the Delaunay triangulation unique, so
		 * a single-threaded, undivided run must give the same set.
		 */
		size_t		nt = tdc_num_triangles(job);
		double	   *canon = canonical_triangles(job);
		double	   *canon2;
		tdc_options ref;

		tdc_job_free(job);
		job = NULL;
		tdc_options_init(&ref);
		ref.threads = 1;
		ref.levels = -1;
		ref.tolerance = opt.tolerance;
		rc = tdc_triangulate(n > 0 ? xy : NULL, n, &ref, &job, err, sizeof(err));
		if (rc != TDC_OK)
			die("reference run failed: %s", err);
		check_job(job, xy, n, &ref);
		if (tdc_num_triangles(job) != nt)
			die("%zu triangles, %zu in the reference run", nt, tdc_num_triangles(job));
		canon2 = canonical_triangles(job);
		for (size_t t = 0; t < nt; t++)
			if (cmp_tri(canon + 6 * t, canon2 + 6 * t) != 0)
				die("triangle set depends on threads/levels/grid");
		free(canon);
		free(canon2);
	}
	tdc_job_free(job);
	free(xy);
	return 0;
}
