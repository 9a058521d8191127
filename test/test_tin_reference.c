/*
 * test_tin_reference.c
 *		The CGAL reference of the value tests (issue 36), and the core
 *		against it.
 *
 * test/fixtures/tin-reference.txt holds samples at a projected offset
 * (around (500000, 4000000)), four polylines among them as breaklines, and
 * at 1,024 held-out pixel centres CGAL's natural neighbour value and the
 * linear value on CGAL's constrained Delaunay triangulation of those
 * polylines, both with exact constructions.  pg_regress (tdc_tin_values)
 * and test/cli.sh compare the SQL functions and ./tdc with these values on
 * machines without CGAL; this file keeps the fixture honest and checks the
 * core where it is made:
 *
 *	- when build/cgal_nn and build/cgal_linear are built (CGAL's headers
 *	  installed), both run again on the file's samples, segments and
 *	  queries and must print the file's values, digit for digit: a fixture
 *	  edited by hand, or made by an older reference, fails here;
 *	- the core's natural neighbour grid over those pixel centres, and its
 *	  linear grid on the TIN with the polylines as breaklines, agree with
 *	  the file within 1e-9 of the value range (at this offset the two
 *	  differ by about 1e-13 m), and the linear grid without the breaklines
 *	  differs from the breakline values (the polylines change the surface).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"
#include "tdc.h"

typedef struct reference
{
	size_t		n,
				k,
				m;
	double	   *xy,				/* n samples */
			   *z;
	uint32_t   *seg;			/* k segments: pairs of sample indices */
	double	   *q;				/* m queries */
	char	  (*text)[2][32];	/* their two values as the file spells them */
	double	   *nn,
			   *brk;
} reference;

static const char *
source_path(const char *rel)
{
	static char path[4096];

	snprintf(path, sizeof(path), "%s/%s", TDC_SOURCE_DIR, rel);
	return path;
}

/* Reads "WORD count" after any comment lines; false on anything else. */
static bool
section(FILE *f, const char *word, size_t *count)
{
	char		line[256],
				w[32];

	while (fgets(line, sizeof(line), f))
	{
		if (line[0] == '#')
			continue;
		return sscanf(line, "%31s %zu", w, count) == 2 && strcmp(w, word) == 0;
	}
	return false;
}

static bool
read_reference(reference *r)
{
	FILE	   *f = fopen(source_path("test/fixtures/tin-reference.txt"), "r");
	bool		ok;

	memset(r, 0, sizeof(*r));
	if (!f)
		return false;
	ok = section(f, "samples", &r->n);
	if (ok)
	{
		r->xy = malloc(2 * r->n * sizeof(double));
		r->z = malloc(r->n * sizeof(double));
		for (size_t i = 0; ok && i < r->n; i++)
			ok = fscanf(f, "%lf %lf %lf ", &r->xy[2 * i], &r->xy[2 * i + 1], &r->z[i]) == 3;
	}
	ok = ok && section(f, "segments", &r->k);
	if (ok)
	{
		r->seg = malloc(2 * r->k * sizeof(uint32_t));
		for (size_t i = 0; ok && i < r->k; i++)
			ok = fscanf(f, "%u %u ", &r->seg[2 * i], &r->seg[2 * i + 1]) == 2 &&
				r->seg[2 * i] < r->n && r->seg[2 * i + 1] < r->n;
	}
	ok = ok && section(f, "queries", &r->m);
	if (ok)
	{
		r->q = malloc(2 * r->m * sizeof(double));
		r->text = malloc(r->m * sizeof(*r->text));
		r->nn = malloc(r->m * sizeof(double));
		r->brk = malloc(r->m * sizeof(double));
		for (size_t i = 0; ok && i < r->m; i++)
		{
			ok = fscanf(f, "%lf %lf %31s %31s ", &r->q[2 * i], &r->q[2 * i + 1],
						r->text[i][0], r->text[i][1]) == 4;
			if (ok)
			{
				r->nn[i] = strtod(r->text[i][0], NULL);
				r->brk[i] = strtod(r->text[i][1], NULL);
			}
		}
	}
	fclose(f);
	return ok;
}

static void
free_reference(reference *r)
{
	free(r->xy);
	free(r->z);
	free(r->seg);
	free(r->q);
	free(r->text);
	free(r->nn);
	free(r->brk);
}

/*
 * Runs a CGAL reference on the file's input (with_segments: cgal_linear's
 * "n k m" form, else cgal_nn's "n m") and counts the lines of its output
 * that differ from the file's column col.  -1 when it could not run.
 */
static long
rerun(const reference *r, const char *tool, bool with_segments, int col)
{
	char		inpath[] = "/tmp/tdc_tinref_XXXXXX",
				cmd[8192],
				buf[64];
	int			fd = mkstemp(inpath);
	FILE	   *f,
			   *p;
	long		differ = 0;
	size_t		i = 0;

	if (fd < 0)
		return -1;
	f = fdopen(fd, "w");
	if (with_segments)
		fprintf(f, "%zu %zu %zu\n", r->n, r->k, r->m);
	else
		fprintf(f, "%zu %zu\n", r->n, r->m);
	for (size_t j = 0; j < r->n; j++)
		fprintf(f, "%.17g %.17g %.17g\n", r->xy[2 * j], r->xy[2 * j + 1], r->z[j]);
	for (size_t j = 0; with_segments && j < r->k; j++)
		fprintf(f, "%u %u\n", r->seg[2 * j], r->seg[2 * j + 1]);
	for (size_t j = 0; j < r->m; j++)
		fprintf(f, "%.17g %.17g\n", r->q[2 * j], r->q[2 * j + 1]);
	fclose(f);
	snprintf(cmd, sizeof(cmd), "%s < %s", source_path(tool), inpath);
	p = popen(cmd, "r");
	while (p && i < r->m && fscanf(p, "%63s", buf) == 1)
		differ += strcmp(buf, r->text[i++][col]) != 0;
	if (!p || pclose(p) != 0 || i != r->m)
		differ = -1;
	unlink(inpath);
	return differ;
}

/* The core's grid over the file's pixel centres; NULL on failure. */
static double *
core_grid(const reference *r, const char *method, bool breaklines)
{
	tdc_options o;
	tdc_job    *job = NULL;
	tdc_cdt    *cdt = NULL;
	tdc_tin    *tin = NULL;
	tdc_interp_spec s;
	tdc_grid_spec g;
	double	   *v = malloc(r->m * sizeof(double));
	uint8_t    *ok = malloc(r->m);
	char		err[256] = "";
	int			rc;

	/* 32 x 32 pixels of 31.25 m whose top left corner is the first query's */
	memset(&g, 0, sizeof(g));
	g.width = g.height = 32;
	g.gt[0] = r->q[0] - 15.625;
	g.gt[1] = 31.25;
	g.gt[3] = r->q[1] + 15.625;
	g.gt[5] = -31.25;
	tdc_options_init(&o);
	rc = tdc_triangulate(r->xy, r->n, &o, &job, err, sizeof(err));
	if (rc == TDC_OK && breaklines)
		rc = tdc_cdt_run(job, r->seg, r->k, &cdt, err, sizeof(err));
	tdc_cdt_free(cdt);
	if (rc == TDC_OK)
		rc = tdc_tin_build(job, r->z, 0, 0, &tin, err, sizeof(err));
	if (rc == TDC_OK)
		rc = tdc_interp_parse(method, &s, err, sizeof(err));
	if (rc == TDC_OK)
		rc = tdc_tin_grid_start(tin, &s, &g, v, ok, err, sizeof(err));
	if (rc == TDC_OK && (rc = tdc_tin_wait(tin, -1)) != TDC_OK)
		snprintf(err, sizeof(err), "%s", tdc_tin_error(tin));
	for (size_t i = 0; rc == TDC_OK && i < r->m; i++)
		if (!ok[i])
			rc = TDC_EINVAL;
	CHECK(rc == TDC_OK, "tin reference: the core's %s grid (%d): %s", method, rc, err);
	tdc_tin_free(tin);
	tdc_job_free(job);
	free(ok);
	if (rc != TDC_OK)
	{
		free(v);
		return NULL;
	}
	return v;
}

/* The largest difference from ref, as a fraction of the samples' value range. */
static double
worst_of_range(const reference *r, const double *v, const double *ref)
{
	double		zmin = INFINITY,
				zmax = -INFINITY,
				worst = 0;

	for (size_t i = 0; i < r->n; i++)
	{
		zmin = fmin(zmin, r->z[i]);
		zmax = fmax(zmax, r->z[i]);
	}
	for (size_t i = 0; i < r->m; i++)
		worst = fmax(worst, fabs(v[i] - ref[i]));
	return worst / (zmax - zmin);
}

void
test_tin_reference(void)
{
	reference	r;
	double	   *nn,
			   *brk,
			   *plain;

	CHECK(read_reference(&r), "tin reference: test/fixtures/tin-reference.txt read");
	if (!r.q)
	{
		free_reference(&r);
		return;
	}
	CHECK(r.n == 1056 && r.k == 48 && r.m == 1024, "tin reference: 1056 samples, 48 segments, "
		  "1024 queries (got %zu, %zu, %zu)", r.n, r.k, r.m);
	if (access(source_path("build/cgal_nn"), X_OK) == 0 &&
		access(source_path("build/cgal_linear"), X_OK) == 0)
	{
		long		dn = rerun(&r, "build/cgal_nn", false, 0),
					dl = rerun(&r, "build/cgal_linear", true, 1);

		CHECK(dn == 0, "tin reference: cgal_nn prints the fixture's natural neighbour values "
			  "(%ld differ; -1: it did not run)", dn);
		CHECK(dl == 0, "tin reference: cgal_linear prints the fixture's breakline values "
			  "(%ld differ; -1: it did not run)", dl);
		printf("tin reference: CGAL reprinted the fixture's %zu natural neighbour and %zu "
			   "breakline values (%ld and %ld differ)\n", r.m, r.m, dn, dl);
	}
	else
		printf("tin reference: build/cgal_nn or build/cgal_linear not built (no CGAL headers): "
			   "the fixture is not checked against CGAL\n");

	nn = core_grid(&r, "natural_neighbor", false);
	brk = core_grid(&r, "linear:breaklines=true", true);
	plain = core_grid(&r, "linear", false);
	if (nn && brk && plain)
	{
		double		wn = worst_of_range(&r, nn, r.nn),
					wb = worst_of_range(&r, brk, r.brk),
					wp = worst_of_range(&r, plain, r.brk);

		CHECK(wn <= 1e-9, "tin reference: natural neighbour within 1e-9 of the value range "
			  "of CGAL's: %.3g", wn);
		CHECK(wb <= 1e-9, "tin reference: breakline linear within 1e-9 of the value range "
			  "of CGAL's: %.3g", wb);
		CHECK(wp > 1e-3, "tin reference: linear without the breaklines differs from CGAL's "
			  "constrained values: %.3g", wp);
		printf("tin reference: %zu pixel centres around (500000, 4000000): natural neighbour "
			   "%.3g, breaklines %.3g of the value range from CGAL's; without the "
			   "breaklines %.3g\n", r.m, wn, wb, wp);
	}
	free(nn);
	free(brk);
	free(plain);
	free_reference(&r);
}
