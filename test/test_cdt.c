/*
 * test_cdt.c
 *		Constrained Delaunay triangulation (cdt.c): every result through the
 *		exact validator (tdc_validate_cdt), degenerate inputs, the rules for
 *		segments (split at sites, overlaps, zero length, crossings), order and
 *		thread independence, cancel, and triangle sets against CGAL's
 *		Constrained_Delaunay_triangulation_2 (build/cgal_cdt, when built).
 */
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "harness.h"
#include "tdc.h"
#include "engine/predicates.h"

static uint64_t rs = 0x9e3779b97f4a7c15ULL;

static double
urand(void)
{
	rs ^= rs << 13;
	rs ^= rs >> 7;
	rs ^= rs << 17;
	return (double) (rs >> 11) / 9007199254740992.0;
}

typedef struct input
{
	double	   *xy;
	size_t		n,
				cap;
	uint32_t   *seg;
	size_t		k,
				kcap;
} input;

static uint32_t
add_pt(input *in, double x, double y)
{
	if (in->n == in->cap)
	{
		in->cap = in->cap ? 2 * in->cap : 64;
		in->xy = realloc(in->xy, in->cap * 16);
	}
	in->xy[2 * in->n] = x;
	in->xy[2 * in->n + 1] = y;
	return (uint32_t) in->n++;
}

static void
add_seg(input *in, uint32_t a, uint32_t b)
{
	if (in->k == in->kcap)
	{
		in->kcap = in->kcap ? 2 * in->kcap : 64;
		in->seg = realloc(in->seg, in->kcap * 8);
	}
	in->seg[2 * in->k] = a;
	in->seg[2 * in->k + 1] = b;
	in->k++;
}

/* A closed ring of m points around (cx, cy), radius r +- noise. */
static void
add_ring(input *in, double cx, double cy, double r, double noise, int m)
{
	uint32_t	first = 0,
				prev = 0;

	for (int i = 0; i < m; i++)
	{
		double		t = 2 * M_PI * i / m,
					rr = r + noise * (urand() - 0.5);
		uint32_t	v = add_pt(in, cx + rr * cos(t), cy + rr * sin(t));

		if (i == 0)
			first = v;
		else
			add_seg(in, prev, v);
		prev = v;
	}
	add_seg(in, prev, first);
}

static void
free_input(input *in)
{
	free(in->xy);
	free(in->seg);
	memset(in, 0, sizeof(*in));
}

/* Triangles as 6 coordinates, rotated to start at the smallest vertex, sorted. */
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

/* Half-edges compared by their two ends only. */
static int
cmp4(const void *a, const void *b)
{
	const double *p = a,
			   *q = b;

	for (int i = 0; i < 4; i++)
		if (p[i] != q[i])
			return p[i] < q[i] ? -1 : 1;
	return 0;
}

static void
normalize(double *t)
{
	int			lo = 0;
	double		c[6];

	for (int j = 1; j < 3; j++)
		if (t[2 * j] < t[2 * lo] || (t[2 * j] == t[2 * lo] && t[2 * j + 1] < t[2 * lo + 1]))
			lo = j;
	for (int j = 0; j < 3; j++)
	{
		c[2 * j] = t[2 * ((lo + j) % 3)];
		c[2 * j + 1] = t[2 * ((lo + j) % 3) + 1];
	}
	memcpy(t, c, sizeof(c));
}

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
		for (int j = 0; j < 3; j++)
			memcpy(t + 6 * i + 2 * j, tdc_site_xy(job, v[j]), 16);
		normalize(t + 6 * i);
		i++;
	}
	qsort(t, i, 48, cmp6);
	*nt = i;
	return t;
}

/* Triangulate, constrain, validate.  Returns the cdt status; keeps job/cdt. */
static int
run(const input *in, int threads, tdc_job **job, tdc_cdt **cdt, char *err)
{
	tdc_options o;
	int			rc;

	tdc_options_init(&o);
	o.threads = threads;
	*cdt = NULL;
	rc = tdc_triangulate(in->xy, in->n, &o, job, err, 256);
	if (rc != TDC_OK)
		return 1000 + rc;
	return tdc_cdt_run(*job, in->seg, in->k, cdt, err, 256);
}

/* The whole check for an input that must succeed. */
static void
check_ok(const char *name, const input *in, int threads)
{
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256] = "";
	int			rc = run(in, threads, &job, &cdt, err);

	CHECK(rc == TDC_OK, "%s: status %d: %s", name, rc, err);
	if (rc == TDC_OK)
	{
		rc = tdc_cdt_validate(cdt, err, sizeof(err));
		CHECK(rc == 0, "%s: not a valid CDT: %s", name, err);
	}
	tdc_cdt_free(cdt);
	tdc_job_free(job);
}

/* Same triangle sets? */
static bool
same_sets(const double *a, size_t na, const double *b, size_t nb)
{
	return na == nb && memcmp(a, b, na * 48) == 0;
}

/* Proper or improper intersection of two segments other than a shared end. */
static bool
touches(const double *a, const double *b, const double *c, const double *d)
{
	double		o1 = tdc_orient2d(a, b, c),
				o2 = tdc_orient2d(a, b, d),
				o3 = tdc_orient2d(c, d, a),
				o4 = tdc_orient2d(c, d, b);
	bool		shared = (a[0] == c[0] && a[1] == c[1]) || (a[0] == d[0] && a[1] == d[1]) ||
		(b[0] == c[0] && b[1] == c[1]) || (b[0] == d[0] && b[1] == d[1]);

	if (o1 == 0 && o2 == 0)
		return true;			/* collinear: reject, overlaps are tested apart */
	if (shared)
		return false;
	return ((o1 >= 0 && o2 <= 0) || (o1 <= 0 && o2 >= 0)) &&
		((o3 >= 0 && o4 <= 0) || (o3 <= 0 && o4 >= 0));
}

/* n random points, then up to k random segments that touch no earlier one. */
static void
random_segments(input *in, size_t n, size_t k, int maxlen_pct)
{
	for (size_t i = 0; i < n; i++)
		add_pt(in, urand(), urand());
	for (size_t tries = 0; tries < 20 * k && in->k < k; tries++)
	{
		uint32_t	a = (uint32_t) (urand() * n),
					b = (uint32_t) (urand() * n);
		const double *pa = in->xy + 2 * a,
				   *pb = in->xy + 2 * b;
		bool		ok = a != b && hypot(pa[0] - pb[0], pa[1] - pb[1]) < maxlen_pct / 100.0;

		for (size_t s = 0; ok && s < in->k; s++)
			if (touches(pa, pb, in->xy + 2 * in->seg[2 * s], in->xy + 2 * in->seg[2 * s + 1]))
				ok = false;
		if (ok)
			add_seg(in, a, b);
	}
}

/* --- CGAL --- */

static const char *
cgal_path(void)
{
	static char path[4096];

	snprintf(path, sizeof(path), "%s/build/cgal_cdt", TDC_SOURCE_DIR);
	return access(path, X_OK) == 0 ? path : NULL;
}

static double *
cgal_tri_set(const input *in, size_t *nt)
{
	char		inpath[] = "/tmp/tdc_cdt_inXXXXXX",
				cmd[8192];
	int			fd = mkstemp(inpath);
	FILE	   *f,
			   *p;
	size_t		cap = 1024,
				i = 0;
	double	   *t = malloc(cap * 48);

	if (fd < 0)
		return NULL;
	f = fdopen(fd, "w");
	fprintf(f, "%zu %zu\n", in->n, in->k);
	for (size_t j = 0; j < in->n; j++)
		fprintf(f, "%.17g %.17g\n", in->xy[2 * j], in->xy[2 * j + 1]);
	for (size_t j = 0; j < in->k; j++)
		fprintf(f, "%u %u\n", in->seg[2 * j], in->seg[2 * j + 1]);
	fclose(f);
	snprintf(cmd, sizeof(cmd), "%s < %s", cgal_path(), inpath);
	p = popen(cmd, "r");
	while (p)
	{
		if (i == cap)
			t = realloc(t, (cap *= 2) * 48);
		if (fscanf(p, "%lf %lf %lf %lf %lf %lf", t + 6 * i, t + 6 * i + 1, t + 6 * i + 2,
				   t + 6 * i + 3, t + 6 * i + 4, t + 6 * i + 5) != 6)
			break;
		normalize(t + 6 * i);
		i++;
	}
	if (!p || pclose(p) != 0)
	{
		free(t);
		t = NULL;
	}
	unlink(inpath);
	qsort(t, i, 48, cmp6);
	*nt = i;
	return t;
}

/*
 * Half-edges of a triangle set as (p, q, apex) coordinate sextuples, sorted
 * by (p, q): the edge across from one is found by looking up (q, p).
 */
static double *
half_edges(const double *t, size_t nt)
{
	double	   *h = malloc((3 * nt + 1) * 48);

	for (size_t i = 0; i < nt; i++)
		for (int j = 0; j < 3; j++)
		{
			double	   *e = h + 18 * i + 6 * j;

			memcpy(e, t + 6 * i + 2 * j, 16);
			memcpy(e + 2, t + 6 * i + 2 * ((j + 1) % 3), 16);
			memcpy(e + 4, t + 6 * i + 2 * ((j + 2) % 3), 16);
		}
	qsort(h, 3 * nt, 48, cmp4);
	return h;
}

/*
 * Do the triangle sets a and b differ only where sites are cocircular?  Every
 * edge of one that the other lacks must lie between two triangles (of its
 * own set) whose four corners are exactly cocircular: such an edge is a
 * diagonal of a cocircular polygon, which a constrained Delaunay
 * triangulation may split either way.  *ndiff is the number of such
 * half-edges, of both sets.
 */
static bool
same_up_to_cocircular(const double *a, size_t na, const double *b, size_t nb, size_t *ndiff)
{
	double	   *ha = half_edges(a, na),
			   *hb = half_edges(b, nb);
	bool		ok = na == nb;

	*ndiff = 0;
	for (int side = 0; side < 2 && ok; side++)
	{
		const double *h = side ? hb : ha,
				   *o = side ? ha : hb;
		size_t		n = 3 * (side ? nb : na),
					no = 3 * (side ? na : nb);

		for (size_t i = 0; i < n && ok; i++)
		{
			const double *e = h + 6 * i,
					   *twin;
			double		key[6];

			if (bsearch(e, o, no, 48, cmp4) != NULL)
				continue;
			memcpy(key, e + 2, 16);
			memcpy(key + 2, e, 16);
			if (bsearch(key, o, no, 48, cmp4) != NULL)
				continue;		/* the other set has it the other way round */
			twin = bsearch(key, h, n, 48, cmp4);
			ok = twin != NULL && tdc_incircle(e, e + 2, e + 4, twin + 4) == 0;
			(*ndiff)++;
		}
	}
	free(ha);
	free(hb);
	return ok;
}

/*
 * Our triangles against CGAL's.  With ties, real data whose sites may be
 * cocircular (a coordinate grid): the sets must be equal but for diagonals of
 * exactly cocircular polygons, where each side may choose (CGAL has no
 * symbolic tie-break); without, they must be equal.
 */
static void
check_cgal_mode(const char *name, const input *in, bool ties)
{
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256] = "";
	size_t		na,
				nb;
	double	   *a,
			   *b;
	int			rc;

	if (!cgal_path())
		return;
	rc = run(in, 0, &job, &cdt, err);
	CHECK(rc == TDC_OK, "%s: %s", name, err);
	if (rc != TDC_OK)
		goto out;
	a = tri_set(job, &na);
	b = cgal_tri_set(in, &nb);
	CHECK(b != NULL, "%s: cgal_cdt failed", name);
	if (b && !ties)
		CHECK(same_sets(a, na, b, nb), "%s: %zu triangles, CGAL %zu, sets differ", name, na, nb);
	else if (b && !same_sets(a, na, b, nb))
	{
		size_t		nd;
		bool		ok = same_up_to_cocircular(a, na, b, nb, &nd);

		CHECK(ok, "%s: %zu triangles, CGAL %zu, sets differ beyond cocircular ties", name, na, nb);
		if (ok)
			printf("cdt: %s: the same triangles as CGAL's but for %zu edges (ours and CGAL's) between cocircular sites\n",
				   name, nd / 2);
	}
	free(a);
	free(b);
out:
	tdc_cdt_free(cdt);
	tdc_job_free(job);
}

static void
check_cgal(const char *name, const input *in)
{
	check_cgal_mode(name, in, false);
}

/* --- the cases --- */

static void
test_random(void)
{
	for (int round = 0; round < 6; round++)
	{
		input		in = {0};
		char		name[64];

		random_segments(&in, 200 + 300 * round, 40 + 30 * round, round < 3 ? 30 : 8);
		snprintf(name, sizeof(name), "random segments %d (%zu pts, %zu segs)", round, in.n, in.k);
		check_ok(name, &in, 0);
		check_cgal(name, &in);
		free_input(&in);
	}
}

/* Nested noisy rings, as contour lines, with free points between. */
static void
contours(input *in, int rings, int per_ring, int free_pts)
{
	for (int r = 1; r <= rings; r++)
		add_ring(in, 0.1 * urand(), 0.1 * urand(), r, 0.3, per_ring + 7 * r);
	for (int i = 0; i < free_pts; i++)
		add_pt(in, (urand() - 0.5) * 2 * rings, (urand() - 0.5) * 2 * rings);
}

static void
test_contours(void)
{
	input		in = {0};

	contours(&in, 12, 60, 300);
	check_ok("nested rings", &in, 0);
	check_cgal("nested rings", &in);
	free_input(&in);

	/* only segments: no free points */
	contours(&in, 8, 40, 0);
	check_ok("rings only", &in, 0);
	check_cgal("rings only", &in);
	free_input(&in);
}

/* A polygon with holes: an outer noisy ring and small rings inside. */
static void
test_holes(void)
{
	input		in = {0};

	add_ring(&in, 0, 0, 10, 0.5, 200);
	for (int i = 0; i < 3; i++)
		for (int j = 0; j < 3; j++)
			add_ring(&in, -5 + 5 * i, -5 + 5 * j, 1.5, 0.2, 17 + i + j);
	for (int i = 0; i < 200; i++)
		add_pt(&in, (urand() - 0.5) * 12, (urand() - 0.5) * 12);
	check_ok("polygon with holes", &in, 0);
	check_cgal("polygon with holes", &in);
	free_input(&in);
}

/*
 * Integer-grid contours: squares and diamonds on a grid, all grid points as
 * sites (cocircular everywhere); validator only (not general position).
 */
static void
test_grid(void)
{
	input		in = {0};
	int			g = 30;
	uint32_t	id[31][31];

	for (int x = 0; x <= g; x++)
		for (int y = 0; y <= g; y++)
			id[x][y] = add_pt(&in, x, y);
	for (int k = 2; k < 15; k += 3)
	{
		/* square of half-size k around (15, 15), unit steps */
		for (int i = -k; i < k; i++)
		{
			add_seg(&in, id[15 + i][15 - k], id[15 + i + 1][15 - k]);
			add_seg(&in, id[15 + k][15 + i], id[15 + k][15 + i + 1]);
			add_seg(&in, id[15 - i][15 + k], id[15 - i - 1][15 + k]);
			add_seg(&in, id[15 - k][15 - i], id[15 - k][15 - i - 1]);
		}
	}
	/* diamonds with long diagonal segments through grid points */
	add_seg(&in, id[15][1], id[16][2]);
	add_seg(&in, id[1][15], id[15][29]);	/* passes through (2,16) ... */
	check_ok("grid contours", &in, 0);
	check_ok("grid contours, 1 thread", &in, 1);
	free_input(&in);

	/* long segments along grid lines, through many sites at once */
	for (int x = 0; x <= g; x++)
		for (int y = 0; y <= g; y++)
			id[x][y] = add_pt(&in, x, y);
	add_seg(&in, id[0][3], id[30][3]);
	add_seg(&in, id[3][0], id[3][30]);	/* meets the previous one at a site */
	add_seg(&in, id[0][0], id[30][30]);	/* the diagonal, through (3,3) too */
	add_seg(&in, id[30][0], id[0][30]);	/* crosses the diagonal at (15,15), a site */
	check_ok("grid lines through sites", &in, 0);
	free_input(&in);
}

static size_t
constraint_edges(const input *in)
{
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256];
	size_t		k = SIZE_MAX;

	if (run(in, 0, &job, &cdt, err) == TDC_OK)
		k = tdc_cdt_num_constraint_edges(cdt);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	return k;
}

static void
test_rules(void)
{
	input		in = {0};
	size_t		k;

	/* a segment through other sites is split there */
	for (int i = 0; i < 6; i++)
		add_pt(&in, i, 0.0);
	add_pt(&in, 2.5, 3);
	add_pt(&in, 2.5, -0.001);
	add_pt(&in, 2.5, 0.001);
	add_seg(&in, 0, 5);
	check_ok("segment through sites", &in, 0);
	k = constraint_edges(&in);
	CHECK(k == 5, "segment through 4 sites: %zu constraint edges, want 5", k);

	/* collinear overlaps merge */
	add_seg(&in, 1, 3);
	add_seg(&in, 2, 4);
	add_seg(&in, 4, 2);
	check_ok("collinear overlaps", &in, 0);
	k = constraint_edges(&in);
	CHECK(k == 5, "overlaps: %zu constraint edges, want 5", k);
	free_input(&in);

	/* zero length, duplicates merged */
	add_pt(&in, 0, 0);
	add_pt(&in, 1, 0);
	add_pt(&in, 0, 1);
	add_pt(&in, 1, 1);
	add_pt(&in, 1, 1);			/* duplicate of 3 */
	add_seg(&in, 3, 4);			/* zero length after merging */
	add_seg(&in, 2, 2);
	add_seg(&in, 0, 4);			/* the diagonal through the duplicate */
	check_ok("zero length and duplicates", &in, 0);
	k = constraint_edges(&in);
	CHECK(k == 1, "duplicates: %zu constraint edges, want 1", k);
	free_input(&in);

	/* segments along the convex hull, both directions, through hull sites */
	add_pt(&in, 0, 0);
	add_pt(&in, 4, 0);
	add_pt(&in, 4, 4);
	add_pt(&in, 0, 4);
	add_pt(&in, 1, 0);
	add_pt(&in, 2, 0);
	add_pt(&in, 2, 2);
	add_pt(&in, 1, 3);
	add_seg(&in, 0, 1);
	add_seg(&in, 2, 1);
	add_seg(&in, 3, 7);
	check_ok("segments along the hull", &in, 0);
	k = constraint_edges(&in);
	CHECK(k == 5, "hull: %zu constraint edges, want 5", k);
	free_input(&in);

	/* a single segment; two points */
	add_pt(&in, 0, 0);
	add_pt(&in, 1, 2);
	add_seg(&in, 0, 1);
	check_ok("single segment", &in, 0);
	CHECK(constraint_edges(&in) == 1, "single segment: one constraint edge");
	free_input(&in);

	/* all collinear, a segment over all of them */
	for (int i = 0; i < 10; i++)
		add_pt(&in, i, 2 * i);
	add_seg(&in, 9, 0);
	check_ok("collinear sites", &in, 0);
	CHECK(constraint_edges(&in) == 9, "collinear: 9 constraint edges");
	free_input(&in);
}

/* A segment the Delaunay triangulation lacks: the thin rhombus. */
static void
test_forced_edge(void)
{
	input		in = {0};
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256];
	int			rc;

	add_pt(&in, 0, 0);
	add_pt(&in, 10, 0);
	add_pt(&in, 5, 1);
	add_pt(&in, 5, -1);
	add_pt(&in, 5, 5);
	add_pt(&in, 5, -5);
	add_seg(&in, 0, 1);			/* crosses the Delaunay edge 2-3 */
	check_ok("forced edge", &in, 0);
	check_cgal("forced edge", &in);

	/* the validator sees that the plain DT lacks it */
	rc = tdc_triangulate(in.xy, in.n, NULL, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "forced edge DT: %s", err);
	rc = tdc_cdt_run(job, in.seg, 0, &cdt, err, sizeof(err));
	CHECK(rc == TDC_OK, "no segments: %s", err);
	{
		size_t		nt;
		double	   *t = tri_set(job, &nt);
		uint32_t   *tri = malloc(nt * 12 + 12);
		double		sites[12];
		uint32_t	seg[2] = {0, 1};

		memcpy(sites, in.xy, sizeof(sites));
		for (size_t i = 0; i < nt; i++)
			for (int j = 0; j < 3; j++)
				for (uint32_t s = 0; s < 6; s++)
					if (sites[2 * s] == t[6 * i + 2 * j] && sites[2 * s + 1] == t[6 * i + 2 * j + 1])
						tri[3 * i + j] = s;
		rc = tdc_validate_cdt(sites, 6, tri, nt, seg, 1, err, sizeof(err));
		CHECK(rc != 0 && strstr(err, "not a chain of edges"),
			  "the DT must fail the CDT validator for segment 0-1: %d %s", rc, err);
		rc = tdc_validate_cdt(sites, 6, tri, nt, seg, 0, err, sizeof(err));
		CHECK(rc == 0, "the DT is a valid CDT without segments: %s", err);
		free(t);
		free(tri);
	}
	tdc_cdt_free(cdt);
	tdc_job_free(job);

	/* and that a constrained result is not Delaunay without its segment */
	rc = run(&in, 0, &job, &cdt, err);
	CHECK(rc == TDC_OK, "forced edge: %s", err);
	{
		size_t		nt;
		double	   *t = tri_set(job, &nt);
		uint32_t   *tri = malloc(nt * 12 + 12);
		double		sites[12];

		memcpy(sites, in.xy, sizeof(sites));
		for (size_t i = 0; i < nt; i++)
			for (int j = 0; j < 3; j++)
				for (uint32_t s = 0; s < 6; s++)
					if (sites[2 * s] == t[6 * i + 2 * j] && sites[2 * s + 1] == t[6 * i + 2 * j + 1])
						tri[3 * i + j] = s;
		rc = tdc_validate_cdt(sites, 6, tri, nt, in.seg, 0, err, sizeof(err));
		CHECK(rc != 0 && strstr(err, "not locally Delaunay"),
			  "the CDT without its segment must fail: %d %s", rc, err);
		free(t);
		free(tri);
	}
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	free_input(&in);
}

static void
test_crossing(void)
{
	input		in = {0};
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256] = "";
	size_t		s1 = 0,
				s2 = 0;
	int			rc;

	add_pt(&in, 0, 0);
	add_pt(&in, 2, 2);
	add_pt(&in, 0, 2);
	add_pt(&in, 2, 0);
	add_pt(&in, 5, 5);
	add_seg(&in, 2, 4);
	add_seg(&in, 0, 1);
	add_seg(&in, 2, 3);			/* crosses 0-1 at (1, 1), no site */
	rc = run(&in, 0, &job, &cdt, err);
	CHECK(rc == TDC_ECROSS, "crossing segments: status %d (%s)", rc, err);
	CHECK(strstr(err, "(0 0) to (2 2)") && strstr(err, "(0 2) to (2 0)"),
		  "the message names both segments: %s", err);
	CHECK(cdt && tdc_cdt_crossing(cdt, &s1, &s2) && s1 == 1 && s2 == 2,
		  "crossing pair %zu %zu, want 1 2", s1, s2);
	tdc_cdt_free(cdt);
	tdc_job_free(job);

	/* at a site both pass through, it is no crossing */
	add_pt(&in, 1, 1);
	rc = run(&in, 0, &job, &cdt, err);
	CHECK(rc == TDC_OK, "crossing at a site: %d %s", rc, err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);

	/* segment index out of range */
	add_seg(&in, 0, 99);
	rc = run(&in, 0, &job, &cdt, err);
	CHECK(rc == TDC_EINVAL, "index out of range: %d %s", rc, err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	free_input(&in);
}

/* The result depends on the sites and segments, not the order nor threads. */
static void
test_unique(void)
{
	input		in = {0},
				rev = {0};
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256];
	size_t		na = 0,
				nb = 0,
				nc = 0;
	double	   *a = NULL,
			   *b = NULL,
			   *c = NULL;
	int			n = tdc_test_quick ? 30000 : 120000;

	/* cocircular everywhere: integer grid contours plus random grid points */
	for (int r = 1; r <= n / 2000; r++)
		add_ring(&in, 0, 0, 10.0 * r, 0, 400);
	for (size_t i = 0; i < in.n; i++)
	{
		in.xy[2 * i] = round(in.xy[2 * i] * 4) / 4;
		in.xy[2 * i + 1] = round(in.xy[2 * i + 1] * 4) / 4;
	}
	while ((int) in.n < n)
		add_pt(&in, round(urand() * 2000 - 1000) / 4, round(urand() * 2000 - 1000) / 4);
	rev = in;
	rev.seg = malloc(in.k * 8);
	for (size_t s = 0; s < in.k; s++)
	{
		rev.seg[2 * s] = in.seg[2 * (in.k - 1 - s) + 1];
		rev.seg[2 * s + 1] = in.seg[2 * (in.k - 1 - s)];
	}

	if (run(&in, 1, &job, &cdt, err) == TDC_OK)
	{
		a = tri_set(job, &na);
		CHECK(tdc_cdt_validate(cdt, err, sizeof(err)) == 0, "rounded rings: %s", err);
	}
	else
		CHECK(0, "rounded rings, 1 thread: %s", err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	if (run(&rev, 2, &job, &cdt, err) == TDC_OK)
		b = tri_set(job, &nb);
	else
		CHECK(0, "rounded rings, 2 threads, reversed: %s", err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	if (run(&in, 3, &job, &cdt, err) == TDC_OK)
		c = tri_set(job, &nc);
	else
		CHECK(0, "rounded rings, 3 threads: %s", err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	CHECK(a && b && same_sets(a, na, b, nb), "reversed segments and 2 threads give other triangles");
	CHECK(a && c && same_sets(a, na, c, nc), "3 threads give other triangles");
	free(a);
	free(b);
	free(c);
	free(rev.seg);
	free_input(&in);
}

/*
 * The parallel pass (cdt.c: stripes of x, at least 8192 segments): rings on
 * a quarter grid (cocircular sites, sites on segments), and to their right
 * long horizontal segments along grid rows among grid points, which cross
 * every stripe there and split at the sites they meet.  1, 2 and 3 threads
 * must give one valid CDT, the same constraint edges, and CGAL's triangles;
 * a crossing added to it must be reported as the same pair.
 */
static void
stripes_input(input *in, int rings, int rows, bool grid)
{
	for (int r = 1; r <= rings; r++)
		add_ring(in, 0, 0, 2.0 * r, grid ? 0 : 0.3, 300 + 10 * r);
	for (size_t i = 0; grid && i < in->n; i++)
	{
		in->xy[2 * i] = round(in->xy[2 * i] * 4) / 4;
		in->xy[2 * i + 1] = round(in->xy[2 * i + 1] * 4) / 4;
	}
	for (int i = 0; i < rows; i++)
	{
		double		y = -2.0 * rings + 4.0 * rings * i / rows;
		uint32_t	a = add_pt(in, 2.5 * rings, y),
					b = add_pt(in, 6.0 * rings, y);

		add_seg(in, a, b);
	}
	for (int i = 0; i < 40 * rings; i++)
	{
		double		x = (2.5 + 3.5 * urand()) * rings,
					y = (urand() - 0.5) * 4 * rings;

		add_pt(in, grid ? round(x * 4) / 4 : x, grid ? round(y * 4) / 4 : y);
	}
}

/* The constraint edges as sorted coordinate quadruples. */
static double *
constraint_set(const tdc_job *job, const tdc_cdt *cdt, size_t *n)
{
	size_t		k = tdc_cdt_num_constraint_edges(cdt),
				i = 0;
	double	   *e = malloc((k + 1) * 48);
	uint32_t	v[2];
	tdc_iter	it = {0};

	while (i < k && tdc_next_constraint_edge(cdt, &it, v))
	{
		memcpy(e + 6 * i, tdc_site_xy(job, v[0]), 16);
		memcpy(e + 6 * i + 2, tdc_site_xy(job, v[1]), 16);
		e[6 * i + 4] = e[6 * i + 5] = 0;
		i++;
	}
	qsort(e, i, 48, cmp6);
	*n = i;
	return e;
}

/* 1, 2 and 3 threads: valid, and the same triangles and constraint edges */
static void
check_threads(const char *name, const input *in)
{
	double	   *t[3] = {NULL},
			   *e[3] = {NULL};
	size_t		nt[3] = {0},
				ne[3] = {0};

	CHECK(in->k >= 8192, "%s: %zu segments, fewer than the parallel pass needs", name, in->k);
	for (int th = 1; th <= 3; th++)
	{
		tdc_job    *job = NULL;
		tdc_cdt    *cdt = NULL;
		char		err[256] = "";
		int			rc = run(in, th, &job, &cdt, err);

		CHECK(rc == TDC_OK, "%s, %d threads: %d %s", name, th, rc, err);
		if (rc == TDC_OK)
		{
			if (th == 2)
				CHECK(tdc_cdt_validate(cdt, err, sizeof(err)) == 0, "%s: not a valid CDT: %s", name, err);
			t[th - 1] = tri_set(job, &nt[th - 1]);
			e[th - 1] = constraint_set(job, cdt, &ne[th - 1]);
		}
		tdc_cdt_free(cdt);
		tdc_job_free(job);
	}
	for (int th = 2; th <= 3; th++)
	{
		CHECK(t[0] && t[th - 1] && same_sets(t[0], nt[0], t[th - 1], nt[th - 1]),
			  "%s: %d threads give other triangles than 1", name, th);
		CHECK(e[0] && e[th - 1] && ne[0] == ne[th - 1] &&
			  memcmp(e[0], e[th - 1], ne[0] * 48) == 0,
			  "%s: %d threads give other constraint edges than 1 (%zu, %zu)",
			  name, th, ne[th - 1], ne[0]);
	}
	for (int i = 0; i < 3; i++)
	{
		free(t[i]);
		free(e[i]);
	}
}

static void
test_stripes(void)
{
	input		in = {0},
				noisy = {0};
	size_t		pair[3][2];
	char		msg[3][256];
	int			rings = tdc_test_quick ? 22 : 40;
	size_t		k0;

	stripes_input(&noisy, rings, 10 * rings, false);
	check_threads("stripes", &noisy);
	check_cgal("stripes", &noisy);
	free_input(&noisy);
	stripes_input(&in, rings, 10 * rings, true);
	check_threads("stripes on a grid", &in);

	/*
	 * Crossings: a chord from ring 3 to ring 5 across ring 4 (inside a
	 * stripe), then a long one from the middle out across every ring (the
	 * serial pass).  Each must be reported as the same pair by 1, 2 and 3
	 * threads.
	 */
	k0 = in.k;
	for (int round = 0; round < 2; round++)
	{
		in.k = k0;
		if (round == 0)
		{
			uint32_t	a = add_pt(&in, 6.0 + 0.013, 0.021),
						b = add_pt(&in, 10.0 - 0.017, 0.029);

			add_seg(&in, a, b);
		}
		else
		{
			uint32_t	a = add_pt(&in, 0.0071, 0.0013),
						b = add_pt(&in, 0.0093, 2.0 * rings + 1.0037);

			add_seg(&in, b, a);
		}
		for (int th = 1; th <= 3; th++)
		{
			tdc_job    *job = NULL;
			tdc_cdt    *cdt = NULL;
			char		err[256] = "";
			int			rc = run(&in, th, &job, &cdt, err);

			CHECK(rc == TDC_ECROSS, "stripes crossing %d, %d threads: status %d (%s)", round, th, rc, err);
			pair[th - 1][0] = pair[th - 1][1] = SIZE_MAX;
			if (cdt)
				tdc_cdt_crossing(cdt, &pair[th - 1][0], &pair[th - 1][1]);
			snprintf(msg[th - 1], sizeof(msg[0]), "%s", err);
			tdc_cdt_free(cdt);
			tdc_job_free(job);
		}
		CHECK(pair[0][1] == in.k - 1,
			  "stripes crossing %d: the pair %zu %zu does not name the chord %zu", round,
			  pair[0][0], pair[0][1], in.k - 1);
		for (int th = 2; th <= 3; th++)
			CHECK(pair[th - 1][0] == pair[0][0] && pair[th - 1][1] == pair[0][1] &&
				  strcmp(msg[th - 1], msg[0]) == 0,
				  "stripes crossing %d: %d threads report %zu %zu, 1 thread %zu %zu",
				  round, th, pair[th - 1][0], pair[th - 1][1], pair[0][0], pair[0][1]);
	}
	free_input(&in);
}

/*
 * Stripe borders under attack: the parallel pass's stripes are 1/16 of the
 * sites' x range wide, here [0, 16], so the borders are x = 1 .. 15.  Along
 * each border, on both sides and a hair from it, vertical segments run up
 * through dense random sites, so that nearly every triangle they cross has
 * a corner on the other side; the pieces go up in input order, left and
 * right in turn, so that the inserters of two neighbouring stripes (each
 * takes its segments in input order) reach the same height of the same
 * border at about the same time.  Tiny segments (already Delaunay edges)
 * make up the 8192 segments the parallel pass needs.  Inserters that
 * flipped such triangles instead of leaving the segment to the serial pass
 * would flip the same triangles at once: a corrupt mesh, an internal error,
 * or a result that is not the one thread's nor CGAL's.  (Whether threads
 * meet there is up to the scheduler: test_ownership is the exact check.)
 */
static void
border_input(input *in, int pieces, int pts)
{
	add_pt(in, 0, 0);
	add_pt(in, 16, 1);
	for (int i = 0; i < pts; i++)
	{
		double		x = 16 * urand(),
					y = urand();

		add_pt(in, x, y);
	}
	for (int j = 0; j < pieces; j++)
		for (int b = 1; b < 16; b++)
			for (int side = -1; side <= 1; side += 2)
			{
				double		x = b + side * (1e-6 + 1e-4 * urand());
				uint32_t	p = add_pt(in, x, (double) j / pieces),
							q = add_pt(in, x, (j + 0.999) / pieces);

				add_seg(in, p, q);
			}
	while (in->k < 8400)
	{
		double		x = 16 * urand(),
					y = urand();

		if (x - floor(x) > 0.01 && x - floor(x) < 0.99)
		{
			uint32_t	p = add_pt(in, x, y),
						q = add_pt(in, x + 1e-7, y + 3e-8);

			add_seg(in, p, q);
		}
	}
}

static void
test_borders(void)
{
	input		in = {0};
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256] = "";
	size_t		par = 0,
				def = 0,
				ser = 0;

	border_input(&in, 10, 40000);
	check_threads("stripe borders", &in);
	check_cgal("stripe borders", &in);
	if (run(&in, 2, &job, &cdt, err) == TDC_OK)
		tdc_cdt_pass_counts(cdt, &par, &def, &ser);
	CHECK(def >= 15 * 2 * 10 / 2,
		  "stripe borders: the stripes inserted %zu and left %zu of %zu; want at least half of the %d along the borders left",
		  par, def, in.k, 15 * 2 * 10);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	free_input(&in);
}

/*
 * The stripes' ownership rule, decided exactly.  Sites span x = [0, 16], so
 * stripe k is [k, k + 1).  Far below, 8400 tiny segments (each joins a site
 * to one 1e-7 away: already Delaunay edges) make the parallel pass run.
 * Above them, "gadgets": at each border, a cluster of sites across it and a
 * segment on each side ending just short of it, rows of them far apart.  A
 * gadget's crossed triangles in the unconstrained triangulation are found
 * here by brute force (a triangle is crossed when the open segment properly
 * crosses one of its edges); the gadgets of one stripe must cross disjoint
 * sets, so each meets its triangles as the unconstrained triangulation has
 * them (nobody else flips them: a triangle with corners in two stripes is
 * never flipped in the parallel pass).  So the rule says exactly which
 * gadgets the stripes must leave to the serial pass: those with a crossed
 * triangle with a corner in another stripe.  tdc_cdt_pass_counts must give
 * that number at 1, 2 and 3 threads, and the result must be the CDT.
 */
#define GADGET_ROWS 4

static int
stripe_of(double x)
{
	return x <= 0 ? 0 : x >= 16 ? 15 : (int) x;
}

/* Does the open segment p-q properly cross the segment a-b? */
static bool
crosses(const double *p, const double *q, const double *a, const double *b)
{
	double		o1 = tdc_orient2d(p, q, a),
				o2 = tdc_orient2d(p, q, b),
				o3 = tdc_orient2d(a, b, p),
				o4 = tdc_orient2d(a, b, q);

	return ((o1 > 0 && o2 < 0) || (o1 < 0 && o2 > 0)) &&
		((o3 > 0 && o4 < 0) || (o3 < 0 && o4 > 0));
}

static void
test_ownership(void)
{
	input		in = {0};
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256] = "";
	size_t		nfill = 8400,
				ngad,
				g0,
				nt = 0,
				expect = 0;
	double	   *t = NULL;
	size_t	   *owner = NULL;
	bool		disjoint = true;

	rs = 0x5eed0f5712e5ULL;	/* its own sequence: the checks below hold for it */
	add_pt(&in, 0, -1);
	add_pt(&in, 16, -1);
	while (in.k < nfill)
	{
		double		x = 16 * urand(),
					y = urand() - 1;
		uint32_t	p,
					q;

		if (x - floor(x) < 1e-5 || x - floor(x) > 1 - 1e-5)
			continue;
		p = add_pt(&in, x, y);
		q = add_pt(&in, x + 1e-7, y + 3e-8);
		add_seg(&in, p, q);
	}
	g0 = in.k;
	for (int row = 0; row < GADGET_ROWS; row++)
		for (int b = 1; b < 16; b++)
		{
			double		y = 1 + row;

			for (int i = 0; i < 30; i++)
				add_pt(&in, b + 0.6 * (urand() - 0.5), y + 0.2 * (urand() - 0.5));
			/*
			 * left of the border: stripe b - 1; right of it: stripe b (one
			 * urand() a statement: the order of arguments is unspecified)
			 */
			for (int side = -1; side <= 1; side += 2)
			{
				double		far = b + 0.3 * side,
							fy = y + 0.015 * (side + 1) + 0.02 * (urand() - 0.5),
							near = b + side * (0.002 + 0.02 * urand()),
							ny = y + 0.015 * (side + 1) + 0.02 * (urand() - 0.5);
				uint32_t	p = add_pt(&in, far, fy),
							q = add_pt(&in, near, ny);

				add_seg(&in, p, q);
			}
		}
	ngad = in.k - g0;

	/* the unconstrained triangles, and which gadget crosses each */
	if (run(&(input) {.xy = in.xy, .n = in.n}, 1, &job, &cdt, err) == TDC_OK)
		t = tri_set(job, &nt);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	CHECK(t != NULL, "ownership: the unconstrained triangulation: %s", err);
	if (t == NULL)
		goto out;
	owner = malloc(nt * sizeof(size_t));
	for (size_t i = 0; i < nt; i++)
		owner[i] = SIZE_MAX;
	for (size_t s = g0; s < in.k; s++)
	{
		const double *p = in.xy + 2 * in.seg[2 * s],
				   *q = in.xy + 2 * in.seg[2 * s + 1];
		int			k = stripe_of(p[0]);
		bool		out_corner = false;

		CHECK(stripe_of(q[0]) == k, "ownership: gadget %zu has its ends in two stripes", s);
		for (size_t i = 0; i < nt; i++)
		{
			const double *v = t + 6 * i;

			if (!crosses(p, q, v, v + 2) && !crosses(p, q, v + 2, v + 4) && !crosses(p, q, v + 4, v))
				continue;
			if (owner[i] != SIZE_MAX &&
				stripe_of(in.xy[2 * in.seg[2 * owner[i]]]) == k)
				disjoint = false;
			owner[i] = s;
			for (int j = 0; j < 3; j++)
				if (stripe_of(v[2 * j]) != k)
					out_corner = true;
		}
		expect += out_corner;
	}
	CHECK(disjoint, "ownership: two gadgets of one stripe cross the same triangle (input unfit)");
	CHECK(expect > 0 && expect < ngad,
		  "ownership: %zu of %zu gadgets reach into another stripe; want some, not all", expect, ngad);
	printf("cdt: ownership: %zu of %zu gadgets reach into another stripe\n", expect, ngad);
	for (int th = 1; th <= 3; th++)
	{
		size_t		par = 0,
					def = 0,
					ser = 0;
		int			rc = run(&in, th, &job, &cdt, err);

		CHECK(rc == TDC_OK, "ownership, %d threads: %d %s", th, rc, err);
		if (rc == TDC_OK)
		{
			tdc_cdt_pass_counts(cdt, &par, &def, &ser);
			CHECK(def == expect && par == in.k - expect && ser == 0,
				  "ownership, %d threads: the stripes inserted %zu and left %zu (and %zu in two stripes); want %zu and %zu (and 0)",
				  th, par, def, ser, in.k - expect, expect);
		}
		tdc_cdt_free(cdt);
		tdc_job_free(job);
	}
	check_threads("ownership gadgets", &in);
	check_cgal("ownership gadgets", &in);
out:
	free(t);
	free(owner);
	free_input(&in);
}

/*
 * The GSHHG shoreline of the Stockholm archipelago (test/fixtures/
 * gshhg-stockholm.wkt: one POLYGON or LINESTRING per line, WKT), real
 * polygons: every ring's segments and the mainland line's, against CGAL and
 * through the validator, at 1, 2 and 3 threads (it has some 16,000 segments,
 * so the parallel stripe pass runs).
 */
static bool
read_wkt_coords(const char **pp, input *in, bool ring)
{
	const char *p = *pp;
	uint32_t	first = UINT32_MAX,
				prev = UINT32_MAX;
	double		fx = 0,
				fy = 0;

	while (*p == ' ')
		p++;
	if (*p++ != '(')
		return false;
	for (;;)
	{
		char	   *end;
		double		x = strtod(p, &end),
					y;

		if (end == p)
			return false;
		p = end;
		y = strtod(p, &end);
		if (end == p)
			return false;
		p = end;
		while (*p == ' ')
			p++;
		/* a ring's closing vertex is its first: close on the first's index */
		if (ring && *p == ')' && first != UINT32_MAX && x == fx && y == fy)
			add_seg(in, prev, first);
		else
		{
			uint32_t	v = add_pt(in, x, y);

			if (prev != UINT32_MAX)
				add_seg(in, prev, v);
			else
			{
				first = v;
				fx = x;
				fy = y;
			}
			prev = v;
		}
		if (*p == ')')
			break;
		if (*p++ != ',')
			return false;
	}
	*pp = p + 1;
	return true;
}

/* Reads the fixture into in; returns the number of geometries, -1 on error. */
static int
read_gshhg(input *in, int *npoly, int *nline)
{
	const char *env = getenv("TDC_FIXTURES_DIR");
	char		path[4096],
			   *line = malloc(1 << 20);
	FILE	   *f;
	int			ngeom = 0;

	*npoly = *nline = 0;
	snprintf(path, sizeof(path), "%s/gshhg-stockholm.wkt",
			 env && env[0] ? env : TDC_SOURCE_DIR "/test/fixtures");
	f = fopen(path, "r");
	if (f == NULL && !(env && env[0]))
		f = fopen("test/fixtures/gshhg-stockholm.wkt", "r");
	if (f == NULL || line == NULL)
	{
		if (f)
			fclose(f);
		free(line);
		return -1;
	}
	/* a line longer than the buffer is no WKT we know: fgets splits it, and then it fails */
	while (fgets(line, 1 << 20, f))
	{
		const char *p = line;
		bool		ok;

		if (line[0] == '\n')
			continue;
		if (strncmp(p, "LINESTRING", 10) == 0)
		{
			p += 10;
			ok = read_wkt_coords(&p, in, false);
			(*nline)++;
		}
		else if (strncmp(p, "POLYGON", 7) == 0)
		{
			p += 7;
			while (*p == ' ')
				p++;
			ok = *p++ == '(';
			while (ok)
			{
				ok = read_wkt_coords(&p, in, true);
				if (!ok || *p != ',')
					break;
				p++;
			}
			ok = ok && *p++ == ')';
			(*npoly)++;
		}
		else
			ok = false;
		if (!ok || (*p != '\n' && *p != '\0'))
		{
			ngeom = -1;
			break;
		}
		ngeom++;
	}
	fclose(f);
	free(line);
	return ngeom;
}

static void
test_gshhg(void)
{
	input		in = {0};
	int			npoly,
				nline,
				ngeom = read_gshhg(&in, &npoly, &nline);

	CHECK(ngeom == 1305 && npoly == 1304 && nline == 1 && in.n == 17548 - 1304,
		  "gshhg-stockholm.wkt: %d geometries (%d polygons, %d lines), %zu vertices; want 1305 (1304, 1), 16244",
		  ngeom, npoly, nline, in.n);
	if (ngeom <= 0)
	{
		free_input(&in);
		return;
	}
	check_threads("GSHHG Stockholm", &in);
	check_cgal_mode("GSHHG Stockholm", &in, true);

	/*
	 * The comparison has teeth: the unconstrained triangulation of the same
	 * sites is not CGAL's constrained one up to ties.
	 */
	if (cgal_path())
	{
		tdc_job    *job = NULL;
		tdc_cdt    *cdt = NULL;
		char		err[256] = "";
		size_t		na = 0,
					nb = 0,
					nd;
		size_t		k = in.k;
		double	   *a = NULL,
				   *b = cgal_tri_set(&in, &nb);

		in.k = 0;
		if (run(&in, 0, &job, &cdt, err) == TDC_OK)
			a = tri_set(job, &na);
		in.k = k;
		CHECK(a && b && !same_up_to_cocircular(a, na, b, nb, &nd),
			  "GSHHG Stockholm: the unconstrained triangles pass for CGAL's constrained ones");
		free(a);
		free(b);
		tdc_cdt_free(cdt);
		tdc_job_free(job);
	}
	free_input(&in);
}

/*
 * Cancel during a long insertion.  Best of up to 3 tries, as the engine's
 * cancel test: a loaded machine may not run the insertion's thread for a
 * while, which is no latency of ours.  The limit is CDT_CANCEL_LIMIT_MS,
 * the engine's CI limit: about 1 to 40 ms quiet, so a margin that load
 * cannot break, while a missing cancel check costs the whole insertion.
 */
#define CDT_CANCEL_LIMIT_MS	250

static void
test_cancel(void)
{
	input		in = {0};
	tdc_job    *job = NULL;
	char		err[256];
	int			rc;
	double		best = 1e9;
	int			canceled = 0;

	/* long segments across many random points: much flipping */
	for (int i = 0; i < 200000; i++)
		add_pt(&in, urand(), urand());
	for (int i = 0; i < 400; i++)
	{
		uint32_t	a = add_pt(&in, -1, i / 400.0),
					b = add_pt(&in, 2, i / 400.0 + 0.0001);

		add_seg(&in, a, b);
	}
	for (int try = 0; try < 3 && best >= CDT_CANCEL_LIMIT_MS * 1e-3 / 5; try++)
	{
		tdc_cdt    *cdt = NULL;
		double		t;

		rc = tdc_triangulate(in.xy, in.n, NULL, &job, err, sizeof(err));
		CHECK(rc == TDC_OK, "cancel input: %s", err);
		rc = tdc_cdt_start(job, in.seg, in.k, &cdt, err, sizeof(err));
		CHECK(rc == TDC_OK, "cdt start: %s", err);
		if (rc == TDC_OK)
		{
			usleep(20000);
			t = tdc_test_now();
			tdc_cdt_cancel(cdt);
			rc = tdc_cdt_wait(cdt, 5000);
			t = tdc_test_now() - t;
			if (rc == TDC_ECANCELED)
			{
				canceled++;
				best = t < best ? t : best;
			}
		}
		tdc_cdt_free(cdt);
		tdc_job_free(job);
	}
	CHECK(canceled > 0, "no insertion was cancelled");
	CHECK(best < CDT_CANCEL_LIMIT_MS * 1e-3, "cancel answered in %.1f ms at best (limit %d)",
		  best * 1e3, CDT_CANCEL_LIMIT_MS);
	printf("cdt: cancel during the insertion answered in %.2f ms\n", best * 1000);
	free_input(&in);
}

/* options.max_memory bounds the insertion's arrays too (tdc_cdt_memory). */
static void
test_memory_limit(void)
{
	input		in = {0};
	tdc_options o;
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	char		err[256];
	int			rc;

	contours(&in, 6, 30, 100);
	tdc_options_init(&o);
	o.max_memory = tdc_estimate_memory(in.n, &o) + tdc_cdt_memory(in.n) / 2;
	rc = tdc_triangulate(in.xy, in.n, &o, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "memory limit: the triangulation fits: %s", err);
	rc = tdc_cdt_start(job, in.seg, in.k, &cdt, err, sizeof(err));
	CHECK(rc == TDC_EMEMLIMIT && cdt == NULL, "memory limit: status %d, want TDC_EMEMLIMIT (%s)", rc, err);
	tdc_job_free(job);

	o.max_memory = tdc_estimate_memory(in.n, &o) + tdc_cdt_memory(in.n);
	rc = tdc_triangulate(in.xy, in.n, &o, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "memory limit: %s", err);
	rc = tdc_cdt_run(job, in.seg, in.k, &cdt, err, sizeof(err));
	CHECK(rc == TDC_OK, "memory limit with room for the insertion: %d %s", rc, err);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	free_input(&in);
}

void
test_cdt(void)
{
	if (!cgal_path())
		printf("cdt: no build/cgal_cdt (libcgal-dev missing?): CGAL comparisons skipped\n");
	test_rules();
	test_forced_edge();
	test_crossing();
	test_random();
	test_contours();
	test_holes();
	test_grid();
	test_unique();
	test_stripes();
	test_ownership();
	test_borders();
	test_gshhg();
	test_memory_limit();
	test_cancel();
}
