/*
 * tin_arbiter.c
 *		The exact arbiter of ./tdc's heights (test/cli.sh, issue 36): what a
 *		grid's pixels and a TIN's contour lines must be, decided in rational
 *		arithmetic (GMP), independently of the code it judges.
 *
 *	tin_arbiter grid SAMPLES TRIANGLES GRID.asc nearest|linear
 *	tin_arbiter contours SAMPLES TRIANGLES CONTOURS BASE INTERVAL
 *
 * SAMPLES is ./tdc's text input ("x y z" a line; of equal x and y the first
 * counts), TRIANGLES what `./tdc -o` wrote for it ("x y z" three times a
 * line): the candidate triangles, which are used only once checked.  Prints
 * one line of figures and exits 0 when every value is right, 1 otherwise
 * (2: bad input).
 *
 *	nearest   every pixel centre's value is the height of the nearest
 *			  sample, found by brute force over all samples: squared
 *			  distances in double for every sample, then the samples within a
 *			  relative 1e-12 of the least compared exactly; ties go to the
 *			  sample first in (x, y) order.
 *	linear	  every pixel centre lies in a candidate triangle (exact
 *			  orientations, boundary included) whose circumcircle holds no
 *			  sample (exact in-circle tests against every sample in the
 *			  circle's bounding box, from the exact centre rounded and widened
 *			  far beyond that rounding): a Delaunay triangle, so its plane's
 *			  value, computed exactly, is a Delaunay value; the pixel's value
 *			  must be within 1e-9 of it.  Cocircular samples (on the circle)
 *			  are allowed and counted: there another Delaunay triangle is as
 *			  right.  Nodata only outside the samples' convex hull.
 *	contours  the candidates must be a Delaunay triangulation: every
 *			  circumcircle empty, every sample a corner, no directed edge
 *			  twice (so no two triangles overlap), and 2n - 2 - h triangles
 *			  (h: the samples on the convex hull's boundary, by an exact
 *			  monotone chain).  When no circumcircle has another sample on it
 *			  either, it is the only one.  Then every edge whose ends lie on
 *			  both sides of a level base + k * interval (a height equal to
 *			  the level counts as above) has its crossing, at the exact linear
 *			  position within 1e-6, among the contour lines' vertices exactly
 *			  once (but for a peak exactly at the level, which no line
 *			  stands for), and every vertex is such a crossing.
 */
#include <gmp.h>
#include <stdbool.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct
{
	double		x,
				y,
				z;
	size_t		ord;			/* input order */
} sample;

static sample *S;				/* distinct samples, in (x, y) order */
static size_t ns;
static size_t (*T)[3];			/* candidate triangles, counter-clockwise */
static signed char *circ;		/* their circumcircles: 2 unknown, 1, 0, -1 */
static size_t nt;
static double bx0, by0, bw, bh;	/* bucket grid over the samples' box */
static int	nb;
static size_t *bstart, *bitem;	/* samples per bucket */
static size_t *tstart, *titem;	/* triangles per bucket (by bounding box) */

static int
cmp_xy(const void *a, const void *b)
{
	const sample *p = a,
			   *q = b;

	if (p->x != q->x)
		return p->x < q->x ? -1 : 1;
	if (p->y != q->y)
		return p->y < q->y ? -1 : 1;
	return p->ord < q->ord ? -1 : p->ord > q->ord;
}

static void
read_samples(const char *path)
{
	FILE	   *f = fopen(path, "r");
	size_t		cap = 1024,
				k = 0;

	if (!f)
		exit(2);
	S = malloc(cap * sizeof(sample));
	while (fscanf(f, "%lf %lf %lf", &S[ns].x, &S[ns].y, &S[ns].z) == 3)
	{
		S[ns].ord = ns;
		if (++ns == cap)
			S = realloc(S, (cap *= 2) * sizeof(sample));
	}
	fclose(f);
	qsort(S, ns, sizeof(sample), cmp_xy);
	for (size_t i = 0; i < ns; i++)		/* of equal x and y, the first */
		if (k == 0 || S[i].x != S[k - 1].x || S[i].y != S[k - 1].y)
			S[k++] = S[i];
	ns = k;
}

static long
find_sample(double x, double y)
{
	size_t		lo = 0,
				hi = ns;

	while (lo < hi)
	{
		size_t		mid = (lo + hi) / 2;

		if (S[mid].x < x || (S[mid].x == x && S[mid].y < y))
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo < ns && S[lo].x == x && S[lo].y == y ? (long) lo : -1;
}

/* --- exact predicates on doubles --- */
static mpq_t q[11];			/* scratch, set up in main */

/* Twice the signed area of (a, b, c), into r. */
static void
area2(mpq_t r, const double *a, const double *b, const double *c)
{
	mpq_t		u,
				v,
				w;

	mpq_inits(u, v, w, NULL);
	mpq_set_d(u, b[0]);
	mpq_set_d(w, a[0]);
	mpq_sub(u, u, w);			/* bx - ax */
	mpq_set_d(v, c[1]);
	mpq_set_d(r, a[1]);
	mpq_sub(v, v, r);			/* cy - ay */
	mpq_mul(u, u, v);
	mpq_set_d(v, b[1]);
	mpq_sub(v, v, r);			/* by - ay */
	mpq_set_d(r, c[0]);
	mpq_sub(r, r, w);			/* cx - ax */
	mpq_mul(v, v, r);
	mpq_sub(r, u, v);
	mpq_clears(u, v, w, NULL);
}

static int
orient(double ax, double ay, double bx, double by, double cx, double cy)
{
	double		a[2] = {ax, ay},
				b[2] = {bx, by},
				c[2] = {cx, cy};

	area2(q[0], a, b, c);
	return mpq_sgn(q[0]);
}

/* > 0: d strictly inside the circle through the counter-clockwise a, b, c. */
static int
incircle(const sample *a, const sample *b, const sample *c, const sample *d)
{
	const sample *p[3] = {a, b, c};
	mpq_t		dx[3],
				dy[3],
				l[3],
				t,
				u,
				det;
	int			s;

	mpq_inits(t, u, det, NULL);
	for (int i = 0; i < 3; i++)
	{
		mpq_inits(dx[i], dy[i], l[i], NULL);
		mpq_set_d(dx[i], p[i]->x);
		mpq_set_d(t, d->x);
		mpq_sub(dx[i], dx[i], t);
		mpq_set_d(dy[i], p[i]->y);
		mpq_set_d(t, d->y);
		mpq_sub(dy[i], dy[i], t);
		mpq_mul(l[i], dx[i], dx[i]);
		mpq_mul(t, dy[i], dy[i]);
		mpq_add(l[i], l[i], t);
	}
	mpq_set_ui(det, 0, 1);
	for (int i = 0; i < 3; i++)
	{
		int			j = (i + 1) % 3,
					k = (i + 2) % 3;

		mpq_mul(t, dx[j], dy[k]);
		mpq_mul(u, dx[k], dy[j]);
		mpq_sub(t, t, u);
		mpq_mul(t, t, l[i]);
		mpq_add(det, det, t);
	}
	s = mpq_sgn(det);
	for (int i = 0; i < 3; i++)
		mpq_clears(dx[i], dy[i], l[i], NULL);
	mpq_clears(t, u, det, NULL);
	return s;
}

/* --- buckets --- */
static int
bucket(double v, double v0, double w)
{
	double		b = floor((v - v0) / w * nb);

	return b < 0 ? 0 : b >= nb ? nb - 1 : (int) b;
}

static void
build_buckets(void)
{
	double		x1 = -INFINITY,
				y1 = -INFINITY;
	size_t	   *cnt;

	bx0 = by0 = INFINITY;
	for (size_t i = 0; i < ns; i++)
	{
		bx0 = fmin(bx0, S[i].x);
		by0 = fmin(by0, S[i].y);
		x1 = fmax(x1, S[i].x);
		y1 = fmax(y1, S[i].y);
	}
	bw = fmax(x1 - bx0, 1e-300);
	bh = fmax(y1 - by0, 1e-300);
	nb = (int) fmax(1, fmin(2048, sqrt((double) ns / 2)));	/* a few samples a bucket up to 1e7 */
	cnt = calloc((size_t) nb * nb + 1, sizeof(size_t));
	bstart = calloc((size_t) nb * nb + 1, sizeof(size_t));
	bitem = malloc(ns * sizeof(size_t));
	for (size_t i = 0; i < ns; i++)
		cnt[bucket(S[i].y, by0, bh) * nb + bucket(S[i].x, bx0, bw)]++;
	for (int b = 0; b < nb * nb; b++)
		bstart[b + 1] = bstart[b] + cnt[b];
	memset(cnt, 0, (size_t) nb * nb * sizeof(size_t));
	for (size_t i = 0; i < ns; i++)
	{
		int			b = bucket(S[i].y, by0, bh) * nb + bucket(S[i].x, bx0, bw);

		bitem[bstart[b] + cnt[b]++] = i;
	}
	/* triangles, by their bounding boxes */
	memset(cnt, 0, (size_t) nb * nb * sizeof(size_t));
	tstart = calloc((size_t) nb * nb + 1, sizeof(size_t));
	for (int pass = 0; pass < 2; pass++)
	{
		for (size_t t = 0; t < nt; t++)
		{
			double		lx = fmin(S[T[t][0]].x, fmin(S[T[t][1]].x, S[T[t][2]].x)),
						hx = fmax(S[T[t][0]].x, fmax(S[T[t][1]].x, S[T[t][2]].x)),
						ly = fmin(S[T[t][0]].y, fmin(S[T[t][1]].y, S[T[t][2]].y)),
						hy = fmax(S[T[t][0]].y, fmax(S[T[t][1]].y, S[T[t][2]].y));

			for (int by = bucket(ly, by0, bh); by <= bucket(hy, by0, bh); by++)
				for (int bx = bucket(lx, bx0, bw); bx <= bucket(hx, bx0, bw); bx++)
				{
					int			b = by * nb + bx;

					if (pass == 0)
						cnt[b]++;
					else
						titem[tstart[b] + cnt[b]++] = t;
				}
		}
		if (pass == 0)
		{
			for (int b = 0; b < nb * nb; b++)
				tstart[b + 1] = tstart[b] + cnt[b];
			titem = malloc((tstart[nb * nb] + 1) * sizeof(size_t));
			memset(cnt, 0, (size_t) nb * nb * sizeof(size_t));
		}
	}
	free(cnt);
}

static void
read_triangles(const char *path)
{
	FILE	   *f = fopen(path, "r");
	size_t		cap = 1024;
	double		v[9];

	if (!f)
		exit(2);
	T = malloc(cap * sizeof(*T));
	while (fscanf(f, "%lf %lf %lf %lf %lf %lf %lf %lf %lf", &v[0], &v[1], &v[2], &v[3], &v[4],
				  &v[5], &v[6], &v[7], &v[8]) == 9)
	{
		long		a = find_sample(v[0], v[1]),
					b = find_sample(v[3], v[4]),
					c = find_sample(v[6], v[7]);
		int			o;

		if (a < 0 || b < 0 || c < 0)
		{
			fprintf(stderr, "tin_arbiter: a triangle corner that is no sample\n");
			exit(1);
		}
		o = orient(S[a].x, S[a].y, S[b].x, S[b].y, S[c].x, S[c].y);
		if (o == 0)
		{
			fprintf(stderr, "tin_arbiter: a degenerate triangle\n");
			exit(1);
		}
		T[nt][0] = a;
		T[nt][1] = o > 0 ? b : c;
		T[nt][2] = o > 0 ? c : b;
		if (++nt == cap)
			T = realloc(T, (cap *= 2) * sizeof(*T));
	}
	fclose(f);
	circ = malloc(nt + 1);
	memset(circ, 2, nt + 1);
}

/* The circumcircle of triangle t against the samples that could lie in it. */
static int
circle(size_t t)
{
	const sample *a = &S[T[t][0]],
			   *b = &S[T[t][1]],
			   *c = &S[T[t][2]];
	double		p[3][2] = {{a->x, a->y}, {b->x, b->y}, {c->x, c->y}};
	mpq_t		d,
				lb,
				lc,
				t1,
				t2,
				ux,
				uy;
	double		cx,
				cy,
				r;
	int			res = 1;

	if (circ[t] != 2)
		return circ[t];
	mpq_inits(d, lb, lc, t1, t2, ux, uy, NULL);
	area2(d, p[0], p[1], p[2]);
	mpq_add(d, d, d);			/* 2 * twice the area */
	/* lb = |b - a|^2, lc = |c - a|^2; centre - a = ((cy-ay) lb - (by-ay) lc, (bx-ax) lc - (cx-ax) lb) / d */
	for (int k = 0; k < 2; k++)
	{
		mpq_t	   *l = k ? &lc : &lb;
		const double *e = k ? p[2] : p[1];

		mpq_set_d(t1, e[0]);
		mpq_set_d(t2, p[0][0]);
		mpq_sub(t1, t1, t2);
		mpq_mul(*l, t1, t1);
		mpq_set_d(t1, e[1]);
		mpq_set_d(t2, p[0][1]);
		mpq_sub(t1, t1, t2);
		mpq_mul(t1, t1, t1);
		mpq_add(*l, *l, t1);
	}
	mpq_set_d(t1, p[2][1]);
	mpq_set_d(t2, p[0][1]);
	mpq_sub(t1, t1, t2);
	mpq_mul(ux, t1, lb);		/* (cy - ay) lb */
	mpq_set_d(t1, p[1][1]);
	mpq_sub(t1, t1, t2);
	mpq_mul(t1, t1, lc);
	mpq_sub(ux, ux, t1);		/* - (by - ay) lc */
	mpq_set_d(t2, p[0][0]);
	mpq_set_d(t1, p[1][0]);
	mpq_sub(t1, t1, t2);
	mpq_mul(uy, t1, lc);		/* (bx - ax) lc */
	mpq_set_d(t1, p[2][0]);
	mpq_sub(t1, t1, t2);
	mpq_mul(t1, t1, lb);
	mpq_sub(uy, uy, t1);		/* - (cx - ax) lb */
	mpq_div(ux, ux, d);
	mpq_div(uy, uy, d);
	cx = a->x + mpq_get_d(ux);
	cy = a->y + mpq_get_d(uy);
	mpq_mul(t1, ux, ux);
	mpq_mul(t2, uy, uy);
	mpq_add(t1, t1, t2);
	r = sqrt(mpq_get_d(t1));
	r = r * (1 + 1e-9) + 1e-9 * (1 + fabs(cx) + fabs(cy));
	for (int byi = bucket(cy - r, by0, bh); byi <= bucket(cy + r, by0, bh); byi++)
		for (int bxi = bucket(cx - r, bx0, bw); bxi <= bucket(cx + r, bx0, bw); bxi++)
		{
			int			bb = byi * nb + bxi;

			for (size_t k = bstart[bb]; k < bstart[bb + 1]; k++)
			{
				size_t		i = bitem[k];
				int			s;

				if (i == T[t][0] || i == T[t][1] || i == T[t][2] ||
					fabs(S[i].x - cx) > r || fabs(S[i].y - cy) > r)
					continue;
				s = incircle(a, b, c, &S[i]);
				if (s > 0)
					res = -1;
				else if (s == 0 && res == 1)
					res = 0;
			}
		}
	mpq_clears(d, lb, lc, t1, t2, ux, uy, NULL);
	return circ[t] = (signed char) res;
}

/* A candidate triangle holding (x, y), boundary included; -1 if none. */
static long
locate(double x, double y)
{
	int			b = bucket(y, by0, bh) * nb + bucket(x, bx0, bw);

	for (size_t k = tstart[b]; k < tstart[b + 1]; k++)
	{
		size_t		t = titem[k];
		const sample *p0 = &S[T[t][0]],
				   *p1 = &S[T[t][1]],
				   *p2 = &S[T[t][2]];

		if (orient(p0->x, p0->y, p1->x, p1->y, x, y) >= 0 &&
			orient(p1->x, p1->y, p2->x, p2->y, x, y) >= 0 &&
			orient(p2->x, p2->y, p0->x, p0->y, x, y) >= 0)
			return (long) t;
	}
	return -1;
}

/* |v - the plane of t at (x, y)|, exactly, rounded to a double. */
static double
linear_error(size_t t, double x, double y, double v)
{
	double		p[3][2],
				qq[2] = {x, y};
	mpq_t		num,
				w,
				z,
				den;
	double		e;

	for (int i = 0; i < 3; i++)
	{
		p[i][0] = S[T[t][i]].x;
		p[i][1] = S[T[t][i]].y;
	}
	mpq_inits(num, w, z, den, NULL);
	area2(den, p[0], p[1], p[2]);
	for (int i = 0; i < 3; i++)
	{
		area2(w, qq, p[(i + 1) % 3], p[(i + 2) % 3]);	/* the weight of vertex i */
		mpq_set_d(z, S[T[t][i]].z);
		mpq_mul(w, w, z);
		mpq_add(num, num, w);
	}
	mpq_div(num, num, den);
	mpq_set_d(z, v);
	mpq_sub(num, num, z);
	mpq_abs(num, num);
	e = mpq_get_d(num);
	mpq_clears(num, w, z, den, NULL);
	return e;
}

/* The sign of |s_j - q|^2 - |s_i - q|^2 = (s_j - s_i).(s_j + s_i - 2q), exactly. */
static int
sqdist_cmp(size_t j, size_t i, double x, double y)
{
	mpq_set_ui(q[10], 0, 1);
	for (int k = 0; k < 2; k++)
	{
		mpq_set_d(q[6], k ? S[j].y : S[j].x);
		mpq_set_d(q[7], k ? S[i].y : S[i].x);
		mpq_sub(q[8], q[6], q[7]);
		mpq_add(q[6], q[6], q[7]);
		mpq_set_d(q[7], k ? y : x);
		mpq_sub(q[6], q[6], q[7]);
		mpq_sub(q[6], q[6], q[7]);
		mpq_mul(q[8], q[8], q[6]);
		mpq_add(q[10], q[10], q[8]);
	}
	return mpq_sgn(q[10]);
}

/*
 * The brute-force nearest sample to (x, y), ties to the first in (x, y)
 * order (S is in that order), and how many are as near (*ties).
 */
static size_t
nearest(double x, double y, size_t *ties)
{
	double		least = INFINITY;
	long		best = -1;

	for (size_t i = 0; i < ns; i++)
		least = fmin(least, (S[i].x - x) * (S[i].x - x) + (S[i].y - y) * (S[i].y - y));
	*ties = 0;
	for (size_t i = 0; i < ns; i++)
	{
		int			c;

		if ((S[i].x - x) * (S[i].x - x) + (S[i].y - y) * (S[i].y - y) > least * (1 + 1e-12))
			continue;
		c = best < 0 ? -1 : sqdist_cmp(i, (size_t) best, x, y);
		if (c < 0)
		{
			best = (long) i;
			*ties = 1;
		}
		else if (c == 0)
			(*ties)++;
	}
	return (size_t) best;
}

/*
 * The convex hull's boundary, counter-clockwise, collinear samples kept (an
 * exact monotone chain over S, which is in (x, y) order): H[0 .. nh), its
 * first point not repeated.
 */
static size_t *H;
static size_t nh;

static void
build_hull(void)
{
	size_t		k = 0;

	H = malloc((2 * ns + 2) * sizeof(size_t));
	for (size_t i = 0; i < ns; i++)		/* lower chain */
	{
		while (k >= 2 && orient(S[H[k - 2]].x, S[H[k - 2]].y, S[H[k - 1]].x, S[H[k - 1]].y,
								S[i].x, S[i].y) < 0)
			k--;
		H[k++] = i;
	}
	for (size_t i = ns - 1, lo = k + 1; i-- > 0;)	/* upper chain */
	{
		while (k >= lo && orient(S[H[k - 2]].x, S[H[k - 2]].y, S[H[k - 1]].x, S[H[k - 1]].y,
								 S[i].x, S[i].y) < 0)
			k--;
		H[k++] = i;
	}
	nh = k - 1;					/* the last point is the first again */
}

/* Is (x, y) strictly outside the hull (right of one of its edges)? */
static bool
outside_hull(double x, double y)
{
	for (size_t k = 0; k < nh; k++)
	{
		const sample *a = &S[H[k]],
				   *b = &S[H[(k + 1) % nh]];

		if (orient(a->x, a->y, b->x, b->y, x, y) < 0)
			return true;
	}
	return false;
}

static int
check_grid(const char *path, const char *method)
{
	FILE	   *f = fopen(path, "r");
	char		key[32];
	double		hdr[6],
				top,
				worst = 0;
	bool		is_nearest = strncmp(method, "nearest", 7) == 0,
				radius0 = strstr(method, "radius=0") != NULL;
	size_t		pixels = 0,
				inside = 0,
				wrong = 0,
				cocircular = 0,
				ties = 0;

	if (!f)
		return 2;
	for (int i = 0; i < 6; i++)		/* ncols nrows xllcorner yllcorner cellsize NODATA_value */
		if (fscanf(f, "%31s %lf", key, &hdr[i]) != 2)
			return 2;
	top = hdr[3] + hdr[1] * hdr[4];	/* as ./tdc has it: the pixel centres from the top */
	for (size_t r = 0; r < (size_t) hdr[1]; r++)
		for (size_t c = 0; c < (size_t) hdr[0]; c++)
		{
			double		v,
						x = hdr[2] + (c + 0.5) * hdr[4],
						y = top + (r + 0.5) * -hdr[4];
			long		t;
			size_t		k;
			bool		ok;

			if (fscanf(f, "%lf", &v) != 1)
				return 2;
			pixels++;
			if (is_nearest)
			{
				size_t		n = nearest(x, y, &k);

				ok = v == S[n].z;
				ties += k > 1;
			}
			else if ((t = locate(x, y)) >= 0)
			{
				int			cc = circle((size_t) t);
				double		e = linear_error((size_t) t, x, y, v);

				inside++;
				cocircular += cc == 0;
				worst = fmax(worst, e);
				ok = cc >= 0 && e <= 1e-9;
			}
			else
			{
				/* no candidate holds it: it must lie outside the hull, where
				 * linear takes the nearest sample (radius -1) or nodata (0) */
				ok = outside_hull(x, y) && (radius0 ? v == hdr[5] : v == S[nearest(x, y, &k)].z);
			}
			if (!ok && wrong++ < 5)
				fprintf(stderr, "tin_arbiter: %s at (%.17g %.17g): %.17g is wrong\n", method, x, y, v);
		}
	fclose(f);
	printf("grid %s: %zu pixels, %zu inside, %zu wrong; largest error against the exact value %.3g, "
		   "%zu on cocircular triangles, %zu nearest ties\n", method, pixels, inside, wrong, worst,
		   cocircular, ties);
	return wrong ? 1 : 0;
}

typedef struct
{
	double		lev,
				x,
				y;
	int			hits;
} lpoint;

static int
cmp_lpoint(const void *a, const void *b)
{
	const lpoint *p = a,
			   *r = b;

	if (p->lev != r->lev)
		return p->lev < r->lev ? -1 : 1;
	if (p->x != r->x)
		return p->x < r->x ? -1 : 1;
	return p->y < r->y ? -1 : p->y > r->y;
}

static int
cmp_edge(const void *a, const void *b)
{
	const size_t *p = a,
			   *r = b;

	return p[0] != r[0] ? (p[0] < r[0] ? -1 : 1) : (p[1] < r[1] ? -1 : p[1] > r[1]);
}

static int
cmp_tri(const void *a, const void *b)
{
	const size_t *p = a,
			   *r = b;

	for (int i = 0; i < 3; i++)
		if (p[i] != r[i])
			return p[i] < r[i] ? -1 : 1;
	return 0;
}

/* Sorted and without repeats; returns the new count. */
static size_t
unique_lpoints(lpoint *v, size_t n)
{
	size_t		k = 0;

	qsort(v, n, sizeof(lpoint), cmp_lpoint);
	for (size_t i = 0; i < n; i++)
		if (k == 0 || cmp_lpoint(&v[i], &v[k - 1]) != 0)
			v[k++] = v[i];
	return k;
}

static int
check_contours(const char *path, double base, double interval)
{
	FILE	   *f = fopen(path, "r");
	size_t		(*E)[2] = malloc(3 * nt * sizeof(*E)),
				ne = 0,
				nx = 0,
				nv = 0,
				capx = 1024,
				capv = 1024,
				strict = 0,
				empty = 0,
				once = 0,
				vertex_hit = 0,
				h;
	lpoint	   *X = malloc(capx * sizeof(lpoint)),
			   *V = malloc(capv * sizeof(lpoint));
	size_t	   (*tri)[3] = malloc(nt * sizeof(*tri));
	double	   *nbmax = malloc((ns + 1) * sizeof(double));
	bool		distinct = true,
				manifold = true,
				all_used = true,
			   *used = calloc(ns + 1, sizeof(bool));
	double		worst = 0;
	char		line[1 << 16];
	mpq_t		t,
				u;
	const double tol = 1e-6;

	if (!f)
		return 2;
	for (size_t i = 0; i < ns; i++)
		nbmax[i] = -INFINITY;
	/* the candidates are a Delaunay triangulation */
	build_hull();
	h = nh;
	for (size_t k = 0; k < nt; k++)
	{
		int			cc = circle(k);

		strict += cc == 1;
		empty += cc >= 0;
		for (int i = 0; i < 3; i++)
		{
			used[T[k][i]] = true;
			E[ne][0] = T[k][i];
			E[ne++][1] = T[k][(i + 1) % 3];
		}
		memcpy(tri[k], T[k], sizeof(tri[k]));
		for (int i = 0; i < 3; i++)		/* rotate the least index first */
			if (tri[k][0] > tri[k][1] || tri[k][0] > tri[k][2])
			{
				size_t		s0 = tri[k][0];

				tri[k][0] = tri[k][1];
				tri[k][1] = tri[k][2];
				tri[k][2] = s0;
			}
	}
	qsort(tri, nt, sizeof(*tri), cmp_tri);
	for (size_t k = 1; k < nt; k++)
		distinct &= memcmp(tri[k], tri[k - 1], sizeof(tri[k])) != 0;
	free(tri);
	qsort(E, ne, sizeof(*E), cmp_edge);		/* directed: none twice */
	for (size_t k = 1; k < ne; k++)
		manifold &= cmp_edge(E[k], E[k - 1]) != 0;
	for (size_t i = 0; i < ns; i++)
		all_used &= used[i];
	free(used);
	/* the edges, undirected, and their crossings with the levels, exactly */
	for (size_t k = 0; k < ne; k++)
		if (E[k][0] > E[k][1])
		{
			size_t		s0 = E[k][0];

			E[k][0] = E[k][1];
			E[k][1] = s0;
		}
	qsort(E, ne, sizeof(*E), cmp_edge);
	for (size_t k = 0; k < ne; k++)
	{
		nbmax[E[k][0]] = fmax(nbmax[E[k][0]], S[E[k][1]].z);
		nbmax[E[k][1]] = fmax(nbmax[E[k][1]], S[E[k][0]].z);
	}
	mpq_inits(t, u, NULL);
	for (size_t k = 0; k < ne; k++)
	{
		const sample *lo,
				   *hi;

		if (k > 0 && E[k][0] == E[k - 1][0] && E[k][1] == E[k - 1][1])
			continue;
		lo = S[E[k][0]].z < S[E[k][1]].z ? &S[E[k][0]] : &S[E[k][1]];
		hi = lo == &S[E[k][0]] ? &S[E[k][1]] : &S[E[k][0]];
		for (double kk = floor((lo->z - base) / interval) - 1; kk <= ceil((hi->z - base) / interval) + 1; kk++)
		{
			double		lev = base + kk * interval;

			if (!(lo->z < lev && hi->z >= lev))
				continue;
			/* a sample at the level whose neighbours are all below it is a
			 * peak there: the level, lowered by an infinitesimal, rings it
			 * with a ring of no size, which no line stands for */
			if (hi->z == lev && nbmax[hi - S] < lev)
				continue;
			/* lo + (lev - lo.z) / (hi.z - lo.z) (hi - lo) */
			if (nx == capx)
				X = realloc(X, (capx *= 2) * sizeof(lpoint));
			X[nx].lev = lev;
			for (int c = 0; c < 2; c++)
			{
				mpq_set_d(t, lev);
				mpq_set_d(u, lo->z);
				mpq_sub(t, t, u);
				mpq_set_d(u, c ? hi->y : hi->x);
				mpq_set_d(q[6], c ? lo->y : lo->x);
				mpq_sub(u, u, q[6]);
				mpq_mul(t, t, u);
				mpq_set_d(u, hi->z);
				mpq_set_d(q[7], lo->z);
				mpq_sub(u, u, q[7]);
				mpq_div(t, t, u);
				mpq_add(t, t, q[6]);
				if (c)
					X[nx].y = mpq_get_d(t);
				else
					X[nx].x = mpq_get_d(t);
			}
			X[nx++].hits = 0;
		}
	}
	mpq_clears(t, u, NULL);
	nx = unique_lpoints(X, nx);
	/* the contour lines' vertices */
	while (fgets(line, sizeof(line), f))
	{
		char	   *p = line,
				   *end;
		double		lev = strtod(p, &end);

		for (p = end;;)
		{
			double		x = strtod(p, &end),
						y;

			if (end == p)
				break;
			y = strtod(p = end, &end);
			if (end == p)
				return 2;
			p = end;
			if (nv == capv)
				V = realloc(V, (capv *= 2) * sizeof(lpoint));
			V[nv].lev = lev;
			V[nv].x = x;
			V[nv].y = y;
			V[nv++].hits = 0;
		}
	}
	fclose(f);
	nv = unique_lpoints(V, nv);
	/* each crossing matches exactly one vertex, each vertex one crossing */
	for (size_t k = 0; k < nx; k++)
	{
		lpoint		key = {X[k].lev, X[k].x - tol, -INFINITY, 0};
		size_t		lo = 0,
					hi = nv,
					n = 0;

		while (lo < hi)
		{
			size_t		mid = (lo + hi) / 2;

			if (cmp_lpoint(&V[mid], &key) < 0)
				lo = mid + 1;
			else
				hi = mid;
		}
		for (size_t j = lo; j < nv && V[j].lev == X[k].lev && V[j].x <= X[k].x + tol; j++)
			if (fabs(V[j].y - X[k].y) <= tol)
			{
				n++;
				V[j].hits++;
				worst = fmax(worst, fmax(fabs(V[j].x - X[k].x), fabs(V[j].y - X[k].y)));
			}
		once += n == 1;
	}
	for (size_t j = 0; j < nv; j++)
		vertex_hit += V[j].hits == 1;
	printf("contours: %zu triangles (%zu with an empty circumcircle, %zu with no other sample on it; "
		   "%s, %s, %s; 2n - 2 - h = %zu), %zu crossings of the levels, %zu contour vertices, %zu "
		   "crossings found once, %zu vertices a crossing once, largest offset %.3g\n", nt, empty, strict,
		   distinct ? "distinct" : "repeated", manifold ? "no edge twice" : "an edge twice",
		   all_used ? "every sample a corner" : "a sample unused", 2 * ns - 2 - h, nx, nv, once,
		   vertex_hit, worst);
	free(E);
	free(X);
	free(V);
	free(nbmax);
	return empty == nt && distinct && manifold && all_used && nt == 2 * ns - 2 - h && once == nx &&
		vertex_hit == nv && nx == nv ? 0 : 1;
}

int
main(int argc, char **argv)
{
	int			rc;

	if (argc < 5 || (strcmp(argv[1], "grid") == 0 ? argc != 6 :
					 strcmp(argv[1], "contours") != 0 || argc != 7))
	{
		fprintf(stderr, "usage: tin_arbiter grid SAMPLES TRIANGLES GRID.asc METHOD\n"
				"       tin_arbiter contours SAMPLES TRIANGLES CONTOURS BASE INTERVAL\n");
		return 2;
	}
	for (int i = 0; i < 11; i++)
		mpq_init(q[i]);
	read_samples(argv[2]);
	read_triangles(argv[3]);
	build_buckets();
	if (strcmp(argv[1], "grid") == 0)
	{
		build_hull();
		rc = check_grid(argv[4], argv[5]);
	}
	else
		rc = check_contours(argv[4], strtod(argv[5], NULL), strtod(argv[6], NULL));
	if (rc == 2)
		fprintf(stderr, "tin_arbiter: cannot read %s\n", argv[4]);
	return rc;
}
