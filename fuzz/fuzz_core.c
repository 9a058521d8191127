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
 * On TDC_OK the result goes through the exact validator exactly as
 * test/test_engine.c run_checked() does: used sites are compacted through
 * tdc_input_site(), triangles through tdc_next_triangle().  Any validator
 * failure, inconsistent count, unexpected status, or (when byte 1 bit 5 is
 * set) a triangle set that differs from the reference run aborts, which
 * libFuzzer reports as a crash with the input saved.
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tdc.h"

#define MAX_RAW_POINTS		4096
#define MAX_EXPANDED		30000

static void
die(const char *fmt, const char *a, const char *b)
{
	fprintf(stderr, "fuzz_core: ");
	fprintf(stderr, fmt, a, b);
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
	uint64_t	z = (*s += 0x9E3779B97F4A7C15ull);

	z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
	z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
	return z ^ (z >> 31);
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

static int
cmp_xy(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	if (p[0] != q[0])
		return p[0] < q[0] ? -1 : 1;
	if (p[1] != q[1])
		return p[1] < q[1] ? -1 : 1;
	return 0;
}

static int
cmp_tri(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	for (int i = 0; i < 6; i++)
		if (p[i] != q[i])
			return p[i] < q[i] ? -1 : 1;
	return 0;
}

static size_t
count_unique(const double *xy, size_t n)
{
	double	   *c = malloc(16 * n + 16);
	size_t		u = 0;

	memcpy(c, xy, 16 * n);
	qsort(c, n, 16, cmp_xy);
	for (size_t i = 0; i < n; i++)
		if (i == 0 || cmp_xy(c + 2 * i, c + 2 * (i - 1)) != 0)
			u++;
	free(c);
	return u;
}

/*
 * Validate a successful job; returns the canonical triangle set (6 doubles
 * per triangle, rotated to start at the smallest vertex, sorted), *ntri set.
 */
static double *
check_job(tdc_job *job, const double *xy, size_t n, const tdc_options *opt,
		  size_t *ntri_out)
{
	uint32_t	lim = tdc_site_id_limit(job);
	size_t		nsites = tdc_num_sites(job);
	size_t		ntri = tdc_num_triangles(job);
	uint32_t   *compact = malloc(sizeof(uint32_t) * ((size_t) lim + 1));
	double	   *sites = malloc(16 * (nsites + 1));
	uint32_t   *tri = malloc(12 * (ntri + 1));
	double	   *canon = malloc(48 * (ntri + 1));
	size_t		m = 0,
				t = 0;
	uint32_t	v[3];
	tdc_iter	it = {0};
	char		err[512];
	char		num[64];

	if (tdc_num_input(job) != n)
		die("num_input %s != %s", "?", "n");
	if (opt->tolerance == 0 && nsites != count_unique(xy, n))
	{
		snprintf(num, sizeof(num), "%zu vs %zu", nsites, count_unique(xy, n));
		die("unique site count differs: %s%s", num, "");
	}
	for (uint32_t s = 0; s < lim; s++)
		compact[s] = UINT32_MAX;
	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);
		const double *sxy;

		if (s >= lim)
			die("input maps to site beyond limit%s%s", "", "");
		sxy = tdc_site_xy(job, s);
		/* without tolerance a site is exactly the input point */
		if (opt->tolerance == 0 && (sxy[0] != xy[2 * i] || sxy[1] != xy[2 * i + 1]))
			die("input point maps to a site with other coordinates%s%s", "", "");
		if (compact[s] == UINT32_MAX)
		{
			if (m >= nsites)
				die("more sites reached than reported%s%s", "", "");
			compact[s] = (uint32_t) m;
			memcpy(sites + 2 * m, sxy, 16);
			m++;
		}
	}
	if (m != nsites)
		die("input map reaches fewer sites than reported%s%s", "", "");
	while (tdc_next_triangle(job, &it, v))
	{
		if (t >= ntri)
			die("more triangles iterated than reported%s%s", "", "");
		for (int k = 0; k < 3; k++)
		{
			if (v[k] >= lim || compact[v[k]] == UINT32_MAX)
				die("triangle uses a site no input maps to%s%s", "", "");
			tri[3 * t + k] = compact[v[k]];
		}
		t++;
	}
	if (t != ntri)
		die("fewer triangles iterated than reported%s%s", "", "");
	if (tdc_validate(sites, m, tri, t, err, sizeof(err)) != 0)
		die("validator: %s%s", err, "");

	/* edges: count must match and every edge must join two used sites */
	{
		uint32_t	e[2];
		size_t		ne = 0;

		it.pos = 0;
		while (tdc_next_edge(job, &it, e))
		{
			if (e[0] >= lim || e[1] >= lim ||
				compact[e[0]] == UINT32_MAX || compact[e[1]] == UINT32_MAX)
				die("edge uses a site no input maps to%s%s", "", "");
			if (ne++ > tdc_num_edges(job))
				die("more edges iterated than reported%s%s", "", "");
		}
		if (ne != tdc_num_edges(job))
			die("edge count differs from the reported one%s%s", "", "");
		/* Euler: a triangulation with t > 0 has e = (3t + h) / 2 */
		if (t > 0 && ne < t)
			die("fewer edges than triangles%s%s", "", "");
	}

	for (size_t i = 0; i < t; i++)
	{
		const double *p[3];
		int			k0 = 0;

		for (int k = 0; k < 3; k++)
			p[k] = sites + 2 * tri[3 * i + k];
		for (int k = 1; k < 3; k++)
			if (cmp_xy(p[k], p[k0]) < 0)
				k0 = k;
		for (int k = 0; k < 3; k++)
			memcpy(canon + 6 * i + 2 * k, p[(k0 + k) % 3], 16);
	}
	qsort(canon, t, 48, cmp_tri);
	free(compact);
	free(sites);
	free(tri);
	*ntri_out = t;
	return canon;
}

/* Equal sets; == so that -0 and 0 (one site) compare equal. */
static bool
same_set(const double *a, const double *b, size_t ntri)
{
	for (size_t i = 0; i < 6 * ntri; i++)
		if (a[i] != b[i])
			return false;
	return true;
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
		{
			char		num[64];

			snprintf(num, sizeof(num), "status %d, n %zu", rc, n);
			die("invalid input or option not rejected with TDC_EINVAL (%s): %s", num, err);
		}
		/* tdc_triangulate keeps the job (with its message) when it failed late */
		if (job != NULL && strcmp(tdc_job_error(job), err) != 0)
			die("job message differs from err: %s / %s", tdc_job_error(job), err);
		tdc_job_free(job);
		free(xy);
		return 0;
	}
	if (rc != TDC_OK)
		die("valid input failed: %s%s", err, "");

	{
		size_t		nt;
		double	   *canon = check_job(job, xy, n, &opt, &nt);

		tdc_job_free(job);
		if (compare)
		{
			tdc_options ref;
			tdc_job    *job2 = NULL;
			size_t		nt2;
			double	   *canon2;

			tdc_options_init(&ref);
			ref.threads = 1;
			ref.levels = -1;
			ref.tolerance = opt.tolerance;
			rc = tdc_triangulate(n > 0 ? xy : NULL, n, &ref, &job2, err, sizeof(err));
			if (rc != TDC_OK)
				die("reference run failed: %s%s", err, "");
			canon2 = check_job(job2, xy, n, &ref, &nt2);
			tdc_job_free(job2);
			if (nt != nt2 || !same_set(canon, canon2, nt))
				die("triangle set depends on threads/levels/grid%s%s", "", "");
			free(canon2);
		}
		free(canon);
	}
	free(xy);
	return 0;
}
