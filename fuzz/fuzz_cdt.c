/*
 * fuzz_cdt.c
 *		libFuzzer target for the constrained triangulation (src/core/cdt/cdt.c).
 *
 * Input layout (missing bytes read as 0):
 *
 *	byte 0		mode (% 3): how point bytes become points
 *				0	one byte per point: x, y in 0..15 (cocircular and
 *					collinear everywhere, duplicates, segments through sites)
 *				1	int16 pairs scaled by 2^-8 (general-ish position)
 *				2	one byte per point: x in 0..15 on the line y = 2x,
 *					plus x, y in 0..15 for every odd byte (collinear runs)
 *	byte 1		bits 0-1: threads - 1 of the triangulation; bit 2: repeat
 *				the segments (every other copy reversed) to at least
 *				REPEAT_SEGS, so that cdt.c's parallel pass by stripes runs
 *	byte 2		number of points (1..128)
 *	then		the points, then the segments: byte pairs, indices mod n
 *
 * Checks, aborting on any failure:
 *	- the status is TDC_OK or TDC_ECROSS, never anything else;
 *	- TDC_OK: the result passes tdc_cdt_validate (constraints present,
 *	  constrained Delaunay, hull covered), and no two segments cross
 *	  properly at a point that is no site (brute force, exact);
 *	- TDC_ECROSS: the two named segments do cross properly;
 *	- the same segments in reverse order, and the triangulation with
 *	  another thread count, give the same status, and on TDC_OK the same
 *	  triangle set: the result depends on the sites and segments only;
 *	  with another thread count alone, TDC_ECROSS names the same pair.
 */
#include <stdarg.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tdc.h"
#include "engine/predicates.h"

#define MAX_PTS		128
#define MAX_SEGS	256
#define REPEAT_SEGS	8192			/* cdt.c's PART_MIN_SEG */

static void die(const char *fmt,...) __attribute__((format(printf, 1, 2), noreturn));

static void
die(const char *fmt,...)
{
	va_list		ap;

	fprintf(stderr, "fuzz_cdt: ");
	va_start(ap, fmt);
	vfprintf(stderr, fmt, ap);
	va_end(ap);
	fprintf(stderr, "\n");
	abort();
}

static int
cmp6(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	for (int i = 0; i < 6; i++)
		if (p[i] != q[i])
			return p[i] < q[i] ? -1 : 1;
	return 0;
}

/* Triangles by coordinates, each rotated to its smallest vertex, sorted. */
static double *
tri_set(tdc_job *job, size_t *nt)
{
	size_t		n = tdc_num_triangles(job),
				i = 0;
	double	   *t = malloc((n + 1) * 48);
	uint32_t	v[3];
	tdc_iter	it = {0};

	while (tdc_next_triangle(job, &it, v))
	{
		int			lo = 0;

		for (int j = 1; j < 3; j++)
		{
			const double *p = tdc_site_xy(job, v[j]),
					   *q = tdc_site_xy(job, v[lo]);

			if (p[0] < q[0] || (p[0] == q[0] && p[1] < q[1]))
				lo = j;
		}
		for (int j = 0; j < 3; j++)
		{
			const double *p = tdc_site_xy(job, v[(lo + j) % 3]);

			t[6 * i + 2 * j] = p[0];
			t[6 * i + 2 * j + 1] = p[1];
		}
		i++;
	}
	qsort(t, i, 48, cmp6);
	*nt = i;
	return t;
}

static bool
on_segment(const double *a, const double *b, const double *p)
{
	if (tdc_orient2d(a, b, p) != 0)
		return false;
	return p[0] >= (a[0] < b[0] ? a[0] : b[0]) && p[0] <= (a[0] > b[0] ? a[0] : b[0]) &&
		p[1] >= (a[1] < b[1] ? a[1] : b[1]) && p[1] <= (a[1] > b[1] ? a[1] : b[1]);
}

static bool
proper_cross(const double *a, const double *b, const double *c, const double *d)
{
	double		o1 = tdc_orient2d(a, b, c),
				o2 = tdc_orient2d(a, b, d),
				o3 = tdc_orient2d(c, d, a),
				o4 = tdc_orient2d(c, d, b);

	return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) &&
		((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

typedef struct result
{
	int			rc;
	double	   *tris;
	size_t		nt;
	size_t		s1,
				s2;
} result;

static result
run(const double *xy, size_t n, const uint32_t *seg, size_t k, int threads)
{
	tdc_options o;
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[512];
	result		r = {0};

	tdc_options_init(&o);
	o.threads = threads;
	if (tdc_triangulate(xy, n, &o, &job, err, sizeof(err)) != TDC_OK)
		die("triangulation failed: %s", err);
	r.rc = tdc_cdt_run(job, seg, k, &cdt, err, sizeof(err));
	if (r.rc == TDC_OK)
	{
		if (tdc_cdt_validate(cdt, err, sizeof(err)) != 0)
			die("invalid constrained triangulation: %s", err);
		r.tris = tri_set(job, &r.nt);
	}
	else if (r.rc == TDC_ECROSS)
	{
		if (!tdc_cdt_crossing(cdt, &r.s1, &r.s2) || r.s1 >= k || r.s2 >= k)
			die("TDC_ECROSS without a valid pair");
	}
	else
		die("unexpected status %d: %s", r.rc, err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	return r;
}

int			LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int
LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
	double		xy[2 * MAX_PTS];
	static uint32_t seg[2 * (REPEAT_SEGS + MAX_SEGS)],
				rev[2 * (REPEAT_SEGS + MAX_SEGS)];
	size_t		pos = 3,
				n,
				k = 0,
				k0;
	int			mode,
				threads;
	result		a,
				b,
				c;

#define BYTE() (pos < size ? data[pos++] : 0)
	if (size < 3)
		return 0;
	mode = data[0] % 3;
	threads = 1 + (data[1] & 3);
	n = 1 + data[2] % MAX_PTS;
	for (size_t i = 0; i < n; i++)
	{
		if (mode == 0)
		{
			uint8_t		v = BYTE();

			xy[2 * i] = v & 15;
			xy[2 * i + 1] = v >> 4;
		}
		else if (mode == 1)
		{
			uint8_t		b0 = BYTE(),
						b1 = BYTE(),
						b2 = BYTE(),
						b3 = BYTE();
			int16_t		x = (int16_t) (b0 | b1 << 8),
						y = (int16_t) (b2 | b3 << 8);

			xy[2 * i] = x / 256.0;
			xy[2 * i + 1] = y / 256.0;
		}
		else
		{
			uint8_t		v = BYTE();

			xy[2 * i] = v & 15;
			xy[2 * i + 1] = (i & 1) ? v >> 4 : 2 * (v & 15);
		}
	}
	while (pos + 1 < size && k < MAX_SEGS)
	{
		seg[2 * k] = data[pos++] % n;
		seg[2 * k + 1] = data[pos++] % n;
		k++;
	}
	k0 = k;
	while ((data[1] & 4) && k0 > 0 && k < REPEAT_SEGS)
	{
		bool		flip = (k / k0) & 1;

		for (size_t s = 0; s < k0; s++, k++)
		{
			seg[2 * k] = seg[2 * s + flip];
			seg[2 * k + 1] = seg[2 * s + !flip];
		}
	}
	for (size_t s = 0; s < k; s++)
	{
		rev[2 * s] = seg[2 * (k - 1 - s) + 1];
		rev[2 * s + 1] = seg[2 * (k - 1 - s)];
	}

	a = run(xy, n, seg, k, threads);
	b = run(xy, n, rev, k, 1 + (threads % 4));
	c = run(xy, n, seg, k, 1);
	if (a.rc != b.rc || a.rc != c.rc)
		die("status %d forward, %d reversed, %d one thread", a.rc, b.rc, c.rc);
	if (a.rc == TDC_OK)
	{
		if (a.nt != b.nt || memcmp(a.tris, b.tris, a.nt * 48) != 0 ||
			a.nt != c.nt || memcmp(a.tris, c.tris, a.nt * 48) != 0)
			die("triangle sets differ with the order or the thread count");
		/* no crossing may have gone unnoticed (the copies add none) */
		for (size_t s = 0; s < k0; s++)
			for (size_t t = s + 1; t < k0; t++)
			{
				const double *p = xy + 2 * seg[2 * s],
						   *q = xy + 2 * seg[2 * s + 1],
						   *u = xy + 2 * seg[2 * t],
						   *v = xy + 2 * seg[2 * t + 1];
				bool		at_site = false;

				if (!proper_cross(p, q, u, v))
					continue;
				for (size_t i = 0; i < n && !at_site; i++)
					at_site = on_segment(p, q, xy + 2 * i) && on_segment(u, v, xy + 2 * i);
				if (!at_site)
					die("segments %zu and %zu cross, but the status is TDC_OK", s, t);
			}
	}
	else
	{
		/* the named pair crosses properly */
		const double *p = xy + 2 * seg[2 * a.s1],
				   *q = xy + 2 * seg[2 * a.s1 + 1],
				   *u = xy + 2 * seg[2 * a.s2],
				   *v = xy + 2 * seg[2 * a.s2 + 1];

		if (!proper_cross(p, q, u, v))
			die("segments %zu and %zu reported as crossing do not cross properly", a.s1, a.s2);
		if (a.s1 != c.s1 || a.s2 != c.s2)
			die("crossing %zu %zu with %d threads, %zu %zu with one", a.s1, a.s2, threads, c.s1, c.s2);
	}
	free(a.tris);
	free(b.tris);
	free(c.tris);
	return 0;
}
