/*
 * test_bounded_labels.c
 *		The caller's labels through the bounded run (tdc_bounded_params.lpath)
 *		and tdc_least_labels on a one-shot job: every vertex of every
 *		emitted triangle comes with the least label of the input points at
 *		its coordinates, and with the z of the first of them.
 *
 * tdc_delaunay_tiled with a tile column labels each triangle by the tile
 * of its smallest vertex, a vertex being owned by the least tile among its
 * copies; the labels ride through the run's files beside the coordinates
 * (and z), so the test makes copies that carry other labels than their
 * first point and lie in every tile of the plan, with and without z, and
 * checks each vertex against a table made here by sorting the input.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "harness.h"
#include "splitmix.h"
#include "tdc.h"

/* A site of the input: its coordinates, the least label and the first z among its points. */
typedef struct site_ref
{
	double		x,
				y;
	int64_t		least;
	double		z;
	size_t		first;
} site_ref;

static int
site_cmp(const void *a, const void *b)
{
	const site_ref *p = a,
			   *q = b;

	if (p->x != q->x)
		return p->x < q->x ? -1 : 1;
	if (p->y != q->y)
		return p->y < q->y ? -1 : 1;
	return p->first < q->first ? -1 : p->first > q->first;
}

/* What emit checks, against the sorted sites. */
typedef struct label_check
{
	const site_ref *sites;
	size_t		nsites;
	size_t		ntri,
				vertices,
				wrong_label,
				wrong_z,
				unknown;
	bool		with_z;
} label_check;

static const site_ref *
find_site(const label_check *c, double x, double y)
{
	size_t		lo = 0,
				hi = c->nsites;

	while (lo < hi)
	{
		size_t		mid = (lo + hi) / 2;
		const site_ref *s = &c->sites[mid];

		if (s->x < x || (s->x == x && s->y < y))
			lo = mid + 1;
		else
			hi = mid;
	}
	return lo < c->nsites && c->sites[lo].x == x && c->sites[lo].y == y ? &c->sites[lo] : NULL;
}

static int
emit_check(void *arg, int tile, const double *q, const double *qz, const int64_t *ql, const size_t *tri,
		   size_t ntri)
{
	label_check *c = arg;

	(void) tile;
	if (ql == NULL)
		return 9;
	for (size_t j = 0; j < 3 * ntri; j++)
	{
		size_t		i = tri[j];
		const site_ref *s = find_site(c, q[2 * i], q[2 * i + 1]);

		c->vertices++;
		if (s == NULL)
			c->unknown++;
		else
		{
			c->wrong_label += ql[i] != s->least;
			c->wrong_z += c->with_z && qz[i] != s->z;
		}
	}
	c->ntri += ntri;
	return 0;
}

static int
write_file(const char *path, const void *p, size_t size, size_t n)
{
	FILE	   *f = fopen(path, "wb");

	if (f == NULL)
		return -1;
	if (fwrite(p, size, n, f) != n)
	{
		fclose(f);
		return -1;
	}
	return fclose(f);
}

/* A labelled run of the files in dir under 16 MB, emitting to emit_check. */
static void
labelled_params(tdc_bounded_params *p, const char *xypath, const char *zpath, const char *lpath, size_t n,
				const tdc_options *opt, const char *dir, label_check *c)
{
	memset(p, 0, sizeof(*p));
	p->xypath = xypath;
	p->zpath = zpath;
	p->lpath = lpath;
	p->n = n;
	p->opt = opt;
	p->limit = (size_t) 16 << 20;
	p->tmpdir = dir;
	p->emit = emit_check;
	p->arg = c;
}

void
test_bounded_labels(void)
{
	size_t		n = tdc_test_quick ? 80000 : 200000;
	double	   *xy = malloc(16 * n),
			   *z = malloc(8 * n);
	int64_t    *lab = malloc(8 * n),
			   *one = malloc(8 * n);
	site_ref   *all = malloc(sizeof(site_ref) * n);
	uint64_t	seed = 37;
	char		dir[4096],
				xypath[4200],
				zpath[4200],
				lpath[4200],
				err[1024];
	const char *base = getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
	size_t		nsites = 0,
				copies = 0;
	tdc_options opt;
	tdc_job    *job = NULL;
	int			rc;

	CHECK(xy && z && lab && one && all, "bounded labels: out of memory");
	if (!(xy && z && lab && one && all))
		goto out;
	snprintf(dir, sizeof(dir), "%s/tdc_test_labels.XXXXXX", base);
	CHECK(mkdtemp(dir) != NULL, "bounded labels: cannot make a directory in %s", base);
	snprintf(xypath, sizeof(xypath), "%s/input.bin", dir);
	snprintf(zpath, sizeof(zpath), "%s/input.z", dir);
	snprintf(lpath, sizeof(lpath), "%s/input.l", dir);

	/*
	 * Uniform points with labels 0 .. 99 at random, z = i; every 7th point
	 * a copy of an earlier one (anywhere, so in any tile) with a label of
	 * its own, sometimes less than the first point's, sometimes more.
	 */
	for (size_t i = 0; i < n; i++)
	{
		if (i > 100 && i % 7 == 0)
		{
			size_t		k = tdc_splitmix64(&seed) % i;

			xy[2 * i] = xy[2 * k];
			xy[2 * i + 1] = xy[2 * k + 1];
			copies++;
		}
		else
		{
			xy[2 * i] = tdc_splitmix64(&seed) / 18446744073709551616.0 * 1000;
			xy[2 * i + 1] = tdc_splitmix64(&seed) / 18446744073709551616.0 * 1000;
		}
		z[i] = (double) i;
		lab[i] = (int64_t) (tdc_splitmix64(&seed) % 100) - 50;
		all[i] = (site_ref) {xy[2 * i], xy[2 * i + 1], lab[i], z[i], i};
	}
	/* the sites: sorted by coordinates, then input order; the first of each keeps the least label */
	qsort(all, n, sizeof(site_ref), site_cmp);
	for (size_t i = 0; i < n; i++)
	{
		if (nsites > 0 && all[nsites - 1].x == all[i].x && all[nsites - 1].y == all[i].y)
		{
			if (all[i].least < all[nsites - 1].least)
				all[nsites - 1].least = all[i].least;
			continue;
		}
		all[nsites++] = all[i];
	}
	CHECK(copies > n / 8 && nsites < n, "bounded labels: %zu copies, %zu sites of %zu points", copies, nsites, n);
	CHECK(write_file(xypath, xy, 16, n) == 0 && write_file(zpath, z, 8, n) == 0 &&
		  write_file(lpath, lab, 8, n) == 0, "bounded labels: cannot write the input in %s", dir);

	/* tdc_least_labels on a one-shot job: each site's first point has its site's least label */
	tdc_options_init(&opt);
	rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
	CHECK(rc == TDC_OK, "bounded labels: one-shot run: %s", err);
	if (rc == TDC_OK)
	{
		size_t		wrong = 0;
		label_check c = {.sites = all, .nsites = nsites};

		memcpy(one, lab, 8 * n);
		tdc_least_labels(job, one);
		for (size_t i = 0; i < nsites; i++)
			wrong += one[all[i].first] != all[i].least;
		/* the other slots keep their own labels */
		for (size_t i = 0; i < n; i++)
		{
			const site_ref *s = find_site(&c, xy[2 * i], xy[2 * i + 1]);

			wrong += s != NULL && s->first != i && one[i] != lab[i];
		}
		CHECK(wrong == 0 && tdc_num_sites(job) == nsites,
			  "bounded labels: tdc_least_labels: %zu wrong of %zu sites (%zu sites in the job)", wrong, nsites,
			  tdc_num_sites(job));
		tdc_job_free(job);
	}

	/* the bounded run in tiles, without z and with it */
	for (int with_z = 0; with_z <= 1; with_z++)
	{
		tdc_bounded_params p;
		tdc_bounded_stats st;
		label_check c = {.sites = all, .nsites = nsites};

		c.with_z = with_z;
		labelled_params(&p, xypath, with_z ? zpath : NULL, lpath, n, &opt, dir, &c);
		p.check_files = true;
		rc = tdc_bounded_run(&p, &st, err, sizeof(err));
		CHECK(rc == TDC_OK, "bounded labels (z %d): run: %d %s", with_z, rc, err);
		CHECK(st.tiles > 1, "bounded labels (z %d): %d tiles, more than 1 expected", with_z, st.tiles);
		CHECK(c.ntri > 0 && c.vertices == 3 * c.ntri && c.unknown == 0,
			  "bounded labels (z %d): %zu triangles, %zu vertices not in the input", with_z, c.ntri, c.unknown);
		CHECK(c.wrong_label == 0, "bounded labels (z %d): %zu of %zu vertices without their least label",
			  with_z, c.wrong_label, c.vertices);
		CHECK(c.wrong_z == 0, "bounded labels (z %d): %zu of %zu vertices without their first z",
			  with_z, c.wrong_z, c.vertices);
	}

	/* a label file shorter than the input */
	{
		tdc_bounded_params p;
		tdc_bounded_stats st;
		label_check c = {.sites = all, .nsites = nsites};

		CHECK(write_file(lpath, lab, 8, n - 1) == 0, "bounded labels: cannot write %s", lpath);
		labelled_params(&p, xypath, NULL, lpath, n, &opt, dir, &c);
		rc = tdc_bounded_run(&p, &st, err, sizeof(err));
		CHECK(rc == TDC_EINVAL && strstr(err, "input.l holds") != NULL && c.ntri == 0,
			  "bounded labels: short label file: %d %s", rc, err);
	}

	unlink(xypath);
	unlink(zpath);
	unlink(lpath);
	CHECK(rmdir(dir) == 0, "bounded labels: %s not empty after the runs", dir);
out:
	free(xy);
	free(z);
	free(lab);
	free(one);
	free(all);
}
