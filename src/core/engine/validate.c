/*
 * validate.c
 *		An exact, independent check of a Delaunay triangulation.
 *
 * It trusts nothing of the engine: it takes the unique sites and a plain
 * triangle list, and checks with the exact predicates that
 *	- every triangle is counter-clockwise and non-degenerate;
 *	- every directed edge occurs once (edges are manifold and consistently
 *	  oriented);
 *	- the boundary edges are exactly the edges of the convex hull computed
 *	  here (Andrew's monotone chain keeping collinear hull sites), so hull
 *	  sites on a straight stretch are vertices of hull triangles;
 *	- every site is used, unless all are collinear (then no triangle);
 *	- ntri == 2m - 2 - h, h counting collinear hull sites;
 *	- every interior edge is locally Delaunay: the opposite site of the
 *	  neighbouring triangle is not strictly inside the circumcircle;
 *	- the triangle areas add up to the hull area (to rounding).
 * Orientation, manifoldness, boundary = hull and the count make the triangles
 * a triangulation of the hull; local Delaunay edges then make it Delaunay
 * (Delaunay's lemma).
 *
 * tdc_validate_cdt() checks a constrained Delaunay triangulation the same
 * way, with segments: each must be a chain of edges from one end to the
 * other, each edge running exactly along the segment towards its far end
 * (so it passes through every site on it, and no triangle crosses it); the
 * edges of these chains are exempt from the local Delaunay test, all others
 * must pass it.  Then the triangulation is the constrained Delaunay one
 * (the constrained Delaunay lemma: every unconstrained edge locally
 * Delaunay implies that no triangle's circumcircle holds a site visible
 * from its interior, constraint edges blocking the view).
 */
#include <math.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "tdc.h"
#include "predicates.h"

static int	fail(char *err, size_t errlen, const char *fmt,...)
			__attribute__((format(printf, 3, 4)));

static int
fail(char *err, size_t errlen, const char *fmt,...)
{
	va_list		ap;

	if (err && errlen)
	{
		va_start(ap, fmt);
		vsnprintf(err, errlen, fmt, ap);
		va_end(ap);
	}
	return -1;
}

/* LSD radix sort of 64-bit keys with a 32-bit payload. */
static bool
radix_sort(uint64_t *key, uint32_t *val, size_t n)
{
	uint64_t   *k2 = malloc(n * sizeof(uint64_t) + 8);
	uint32_t   *v2 = malloc(n * sizeof(uint32_t) + 4);

	if (!k2 || !v2)
	{
		free(k2);
		free(v2);
		return false;
	}
	for (int shift = 0; shift < 64; shift += 16)
	{
		size_t		count[65537] = {0};

		for (size_t i = 0; i < n; i++)
			count[((key[i] >> shift) & 0xffff) + 1]++;
		if (count[1] == n)
			continue;			/* digit all zero */
		for (int d = 0; d < 65536; d++)
			count[d + 1] += count[d];
		for (size_t i = 0; i < n; i++)
		{
			size_t		p = count[(key[i] >> shift) & 0xffff]++;

			k2[p] = key[i];
			v2[p] = val[i];
		}
		memcpy(key, k2, n * sizeof(uint64_t));
		memcpy(val, v2, n * sizeof(uint32_t));
	}
	free(k2);
	free(v2);
	return true;
}

/*
 * Lexicographic (x, y) order of two site indices into the sites "s".  The
 * sites come as qsort_r's argument, not through a static: validations may
 * run in several threads at once.
 */
static int
cmp_site(const void *a, const void *b, void *s)
{
	const double *p = (const double *) s + 2 * (size_t) *(const uint32_t *) a;
	const double *q = (const double *) s + 2 * (size_t) *(const uint32_t *) b;

	if (p[0] != q[0])
		return p[0] < q[0] ? -1 : 1;
	if (p[1] != q[1])
		return p[1] < q[1] ? -1 : 1;
	return 0;
}

/* Binary search for directed edge (a, b) in the sorted keys. */
static size_t
find_edge(const uint64_t *key, size_t n, uint32_t a, uint32_t b)
{
	uint64_t	k = ((uint64_t) a << 32) | b;
	size_t		lo = 0,
				hi = n;

	while (lo < hi)
	{
		size_t		mid = lo + (hi - lo) / 2;

		if (key[mid] < k)
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo < n && key[lo] == k ? lo : SIZE_MAX;
}

/*
 * p lies exactly on the line of a-b: is it strictly between them?  By
 * coordinate comparisons along the longer-varying axis, so exact.
 */
static bool
strictly_between(const double *a, const double *p, const double *b)
{
	int			k = a[0] != b[0] ? 0 : 1;

	return (a[k] < p[k] && p[k] < b[k]) || (b[k] < p[k] && p[k] < a[k]);
}

/*
 * Follow segment a-b along directed edges (keys sorted) from a, marking the
 * edges it uses (both directions) in "on".  Returns false when some step
 * finds no edge out of the current site along the segment.
 */
static bool
walk_segment(const double *S, const uint64_t *key, size_t ne, unsigned char *on,
			 uint32_t a, uint32_t b)
{
	uint32_t	cur = a;

	while (cur != b)
	{
		uint64_t	k0 = (uint64_t) cur << 32;
		size_t		lo = 0,
					hi = ne;
		uint32_t	next = UINT32_MAX;

		while (lo < hi)
		{
			size_t		mid = lo + (hi - lo) / 2;

			if (key[mid] < k0)
				lo = mid + 1;
			else
				hi = mid;
		}
		for (size_t i = lo; i < ne && (key[i] >> 32) == cur; i++)
		{
			uint32_t	c = (uint32_t) key[i];

			if (c == b ||
				(tdc_orient2d(S + 2 * (size_t) a, S + 2 * (size_t) b, S + 2 * (size_t) c) == 0 &&
				 strictly_between(S + 2 * (size_t) cur, S + 2 * (size_t) c, S + 2 * (size_t) b)))
			{
				size_t		j = find_edge(key, ne, c, cur);

				next = c;
				on[i] = 1;
				if (j != SIZE_MAX)
					on[j] = 1;
				break;
			}
		}
		if (next == UINT32_MAX)
			return false;
		cur = next;
	}
	return true;
}

static int
validate(const double *S, size_t m, const uint32_t *tri, size_t ntri,
		 const uint32_t *seg, size_t nseg, char *err, size_t errlen)
{
	unsigned char *on = NULL;	/* per directed edge: on a segment */

	uint32_t   *order = NULL,
			   *hull = NULL,
			   *val = NULL;
	uint64_t   *key = NULL;
	unsigned char *used = NULL;
	size_t		h = 0,
				nb = 0,
				ne = 3 * ntri;
	bool		collinear = true;
	double		area = 0,
				hull_area = 0,
				slack = 0;		/* magnitude of the summed terms, for rounding */
	int			rc = 0;

#define P(i) (S + 2 * (size_t) (i))
#define BAIL(...) do { rc = fail(err, errlen, __VA_ARGS__); goto done; } while (0)

	for (size_t i = 2; i < m && collinear; i++)
		if (tdc_orient2d(P(0), P(1), P(i)) != 0)
			collinear = false;
	if (m < 3)
		collinear = true;

	/* triangles */
	for (size_t t = 0; t < ntri; t++)
	{
		const uint32_t *v = tri + 3 * t;

		if (v[0] >= m || v[1] >= m || v[2] >= m)
			BAIL("triangle %zu has a vertex index out of range", t);
		if (!(tdc_orient2d(P(v[0]), P(v[1]), P(v[2])) > 0))
			BAIL("triangle %zu (%u %u %u) is not counter-clockwise", t, v[0], v[1], v[2]);
		{
			double		l = (P(v[1])[0] - P(v[0])[0]) * (P(v[2])[1] - P(v[0])[1]),
						r = (P(v[1])[1] - P(v[0])[1]) * (P(v[2])[0] - P(v[0])[0]);

			area += 0.5 * (l - r);
			slack += fabs(l) + fabs(r);
		}
	}
	if (collinear)
	{
		if (ntri != 0)
			BAIL("all %zu sites are collinear but there are %zu triangles", m, ntri);
		goto done;
	}

	/* convex hull, collinear sites included */
	order = malloc(m * sizeof(uint32_t));
	hull = malloc((2 * m + 1) * sizeof(uint32_t));
	if (!order || !hull)
		BAIL("out of memory");
	for (size_t i = 0; i < m; i++)
		order[i] = (uint32_t) i;
	qsort_r(order, m, sizeof(uint32_t), cmp_site, (void *) S);
	for (size_t i = 1; i < m; i++)
		if (cmp_site(&order[i - 1], &order[i], (void *) S) == 0)
			BAIL("sites %u and %u are equal", order[i - 1], order[i]);
	for (size_t i = 0; i < m; i++)
	{
		while (h >= 2 && tdc_orient2d(P(hull[h - 2]), P(hull[h - 1]), P(order[i])) < 0)
			h--;
		hull[h++] = order[i];
	}
	for (size_t i = m - 1, lower = h + 1; i-- > 0;)
	{
		while (h >= lower && tdc_orient2d(P(hull[h - 2]), P(hull[h - 1]), P(order[i])) < 0)
			h--;
		hull[h++] = order[i];
	}
	h--;						/* the first site closes the loop */
	for (size_t i = 0; i < h; i++)
	{
		const double *o = P(hull[0]),
				   *a = P(hull[i]),
				   *b = P(hull[i + 1]);
		double		l = (a[0] - o[0]) * (b[1] - o[1]),
					r = (a[1] - o[1]) * (b[0] - o[0]);

		hull_area += 0.5 * (l - r);
		slack += fabs(l) + fabs(r);
	}

	if (ntri != 2 * m - 2 - h)
		BAIL("%zu triangles, but 2n - 2 - h = %zu (n = %zu, h = %zu)", ntri, 2 * m - 2 - h, m, h);

	/* directed edges */
	key = malloc(ne * sizeof(uint64_t) + 8);
	val = malloc(ne * sizeof(uint32_t) + 4);
	used = calloc(m, 1);
	if (!key || !val || !used)
		BAIL("out of memory");
	for (size_t t = 0; t < ntri; t++)
		for (int j = 0; j < 3; j++)
		{
			uint32_t	a = tri[3 * t + j],
						b = tri[3 * t + (j + 1) % 3];

			key[3 * t + j] = ((uint64_t) a << 32) | b;
			val[3 * t + j] = (uint32_t) (3 * t + (j + 2) % 3);	/* opposite corner */
			used[a] = 1;
		}
	if (!radix_sort(key, val, ne))
		BAIL("out of memory");
	for (size_t i = 1; i < ne; i++)
		if (key[i] == key[i - 1])
			BAIL("directed edge %u->%u occurs twice: not a manifold triangulation",
				 (uint32_t) (key[i] >> 32), (uint32_t) key[i]);
	if (nseg > 0)
	{
		on = calloc(ne + 1, 1);
		if (!on)
			BAIL("out of memory");
	}
	for (size_t s = 0; s < nseg; s++)
	{
		uint32_t	a = seg[2 * s],
					b = seg[2 * s + 1];

		if (a >= m || b >= m)
			BAIL("segment %zu has a site index out of range", s);
		if (a == b)
			continue;
		/* a segment along the hull has its edges in one direction only */
		if (!walk_segment(S, key, ne, on, a, b) && !walk_segment(S, key, ne, on, b, a))
			BAIL("segment %zu (%.17g %.17g -> %.17g %.17g) is not a chain of edges",
				 s, P(a)[0], P(a)[1], P(b)[0], P(b)[1]);
	}
	for (size_t i = 0; i < m; i++)
		if (!used[i])
			BAIL("site %zu (%.17g %.17g) is in no triangle", i, P(i)[0], P(i)[1]);

	for (size_t i = 0; i < ne; i++)
	{
		uint32_t	a = (uint32_t) (key[i] >> 32),
					b = (uint32_t) key[i];
		size_t		j = find_edge(key, ne, b, a);

		if (j == SIZE_MAX)
		{
			nb++;
			continue;
		}
		if (a < b && !(on && on[i]))
		{
			uint32_t	c = tri[val[i]],
						d = tri[val[j]];

			if (tdc_incircle(P(a), P(b), P(c), P(d)) > 0)
				BAIL("edge %u-%u is not locally Delaunay: site %u is inside the circle of %u %u %u",
					 a, b, d, a, b, c);
		}
	}
	if (nb != h)
		BAIL("%zu boundary edges but the convex hull has %zu", nb, h);
	for (size_t i = 0; i < h; i++)
	{
		size_t		j = find_edge(key, ne, hull[i], hull[i + 1]);

		if (j == SIZE_MAX || find_edge(key, ne, hull[i + 1], hull[i]) != SIZE_MAX)
			BAIL("convex hull edge %u->%u (%.17g %.17g -> %.17g %.17g) is not a boundary edge",
				 hull[i], hull[i + 1], P(hull[i])[0], P(hull[i])[1],
				 P(hull[i + 1])[0], P(hull[i + 1])[1]);
	}
	if (fabs(area - hull_area) > 1e-9 * fabs(hull_area) + 1e-12 * slack)
		BAIL("triangle areas sum to %.17g, hull area is %.17g", area, hull_area);

done:
	free(order);
	free(hull);
	free(key);
	free(val);
	free(used);
	free(on);
	return rc;
#undef P
#undef BAIL
}

int
tdc_validate(const double *S, size_t m, const uint32_t *tri, size_t ntri,
			 char *err, size_t errlen)
{
	return validate(S, m, tri, ntri, NULL, 0, err, errlen);
}

int
tdc_validate_cdt(const double *S, size_t m, const uint32_t *tri, size_t ntri,
				 const uint32_t *seg, size_t nseg, char *err, size_t errlen)
{
	return validate(S, m, tri, ntri, seg, nseg, err, errlen);
}

int
tdc_validate_job(const tdc_job *job, char *err, size_t errlen)
{
	size_t		n = tdc_num_input(job),
				m = 0,
				t = 0;
	uint32_t	lim = tdc_site_id_limit(job),
			   *dense = malloc(sizeof(uint32_t) * ((size_t) lim + 1)),
			   *tri = malloc(12 * (tdc_num_triangles(job) + 1)),
				v[3];
	double	   *sites = malloc(16 * (tdc_num_sites(job) + 1));
	tdc_iter	it = {0};
	int			rc;

	if (!dense || !tri || !sites)
	{
		rc = fail(err, errlen, "out of memory for validation");
		goto done;
	}
	for (uint32_t s = 0; s < lim; s++)
		dense[s] = UINT32_MAX;
	for (size_t i = 0; i < n; i++)
	{
		uint32_t	s = tdc_input_site(job, i);

		if (s >= lim)
		{
			rc = fail(err, errlen, "input %zu maps to site %u, beyond %u", i, s, lim);
			goto done;
		}
		if (dense[s] == UINT32_MAX)
		{
			if (m == tdc_num_sites(job))
			{
				rc = fail(err, errlen, "more sites reached from the input than the %zu reported",
						  tdc_num_sites(job));
				goto done;
			}
			dense[s] = (uint32_t) m;
			memcpy(sites + 2 * m++, tdc_site_xy(job, s), 16);
		}
	}
	if (m != tdc_num_sites(job))
	{
		rc = fail(err, errlen, "the input reaches %zu sites, %zu reported", m, tdc_num_sites(job));
		goto done;
	}
	while (tdc_next_triangle(job, &it, v))
	{
		if (t == tdc_num_triangles(job))
		{
			rc = fail(err, errlen, "more triangles than the %zu reported", tdc_num_triangles(job));
			goto done;
		}
		for (int k = 0; k < 3; k++)
		{
			if (v[k] >= lim || dense[v[k]] == UINT32_MAX)
			{
				rc = fail(err, errlen, "a triangle uses site %u, which no input reaches", v[k]);
				goto done;
			}
			tri[3 * t + k] = dense[v[k]];
		}
		t++;
	}
	if (t != tdc_num_triangles(job))
		rc = fail(err, errlen, "%zu triangles iterated, %zu reported", t, tdc_num_triangles(job));
	else
		rc = tdc_validate(sites, m, tri, t, err, errlen);
done:
	free(dense);
	free(tri);
	free(sites);
	return rc;
}
