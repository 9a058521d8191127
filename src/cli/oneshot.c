/*
 * oneshot.c
 *		The run of ./tdc with the whole input in memory: the triangulation,
 *		then with --segments the constrained one, with --voronoi the cells;
 *		its output (-o), its --stats lines and its --validate check.
 */
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

#include "cli.h"

static double
seconds_between(const struct timespec *t0, const struct timespec *t1)
{
	return (t1->tv_sec - t0->tv_sec) + (t1->tv_nsec - t0->tv_nsec) * 1e-9;
}

/*
 * Cells written without -o, timed: a count, a pad, then the ring closed,
 * the layout of a PostGIS polygon's ring.
 */
static size_t
cli_cell_size(void *arg, size_t m)
{
	return 8 + 16 * (m + 1);
}

static void
cli_cell_write(void *arg, char *dst, const double *xy, size_t m)
{
	uint32_t	h[2] = {(uint32_t) (m + 1), 0};

	memcpy(dst, h, 8);
	memcpy(dst + 8, xy, 16 * m);
	memcpy(dst + 8 + 16 * m, xy, 16);
}

/* --segments: r->cdt, the constrained triangulation of r->job */
static void
constrain(const cli_args *a, size_t n, oneshot *r)
{
	struct timespec t0,
				t1;
	char		err[512];
	int			rc;

	r->seg = read_segments(a->segpath, n, &r->nseg);
	clock_gettime(CLOCK_MONOTONIC, &t0);
	rc = tdc_cdt_run(r->job, r->seg, r->nseg, &r->cdt, err, sizeof(err));
	clock_gettime(CLOCK_MONOTONIC, &t1);
	r->constrain_s = seconds_between(&t0, &t1);
	if (rc != TDC_OK)
	{
		tdc_cdt_free(r->cdt);
		tdc_job_free(r->job);
		die(1, "%s", err);
	}
}

/*
 * --voronoi: r->vor, the cells of r->job clipped to GEOS's default
 * envelope; built to be written with -o, else sized and written into one
 * buffer (r->cells), as the extension does.
 */
static void
voronoi(const cli_args *a, oneshot *r)
{
	double		env[4];
	struct timespec t0,
				t1;
	char		err[512];
	int			rc;

	err[0] = '\0';
	clock_gettime(CLOCK_MONOTONIC, &t0);
	tdc_voronoi_default_env(r->job, env);
	if (a->outpath)
		rc = tdc_voronoi_build(r->job, env, a->opt.threads, &r->vor, err, sizeof(err));
	else
	{
		tdc_cell_writer w = {cli_cell_size, cli_cell_write, NULL};

		rc = tdc_voronoi_start_emit(r->job, env, a->opt.threads, &w, &r->vor, err, sizeof(err));
		if (rc == TDC_OK)
			rc = tdc_voronoi_wait(r->vor, -1);
		if (rc == TDC_OK)
		{
			r->cells = malloc(tdc_voronoi_emit_size(r->vor, NULL) + 1);
			rc = r->cells == NULL ? TDC_ENOMEM : tdc_voronoi_emit(r->vor, r->cells, err, sizeof(err));
		}
		if (rc == TDC_OK)
			rc = tdc_voronoi_wait(r->vor, -1);
		if (rc != TDC_OK && r->vor && !err[0])
			snprintf(err, sizeof(err), "%s", tdc_voronoi_error(r->vor));
	}
	clock_gettime(CLOCK_MONOTONIC, &t1);
	if (rc != TDC_OK)
	{
		tdc_voronoi_free(r->vor);
		tdc_job_free(r->job);
		die(1, "%s", err);
	}
	r->vor_seconds = seconds_between(&t0, &t1);
}

/* The run: the triangulation of in, then the constraints or the cells. */
void
oneshot_run(const cli_args *a, const cli_input *in, oneshot *r)
{
	char		err[512];

	memset(r, 0, sizeof(*r));
	if (tdc_triangulate(in->xy, in->n, &a->opt, &r->job, err, sizeof(err)) != TDC_OK)
	{
		tdc_job_free(r->job);
		die(1, "%s", err);
	}
	if (a->segpath && a->voronoi)
		die(2, "--voronoi of a constrained triangulation is not supported%s", "");
	if (a->segpath)
		constrain(a, in->n, r);
	if (a->voronoi)
		voronoi(a, r);
}

static FILE *
open_output(const char *outpath)
{
	return strcmp(outpath, "-") == 0 ? stdout : fopen(outpath, "w");
}

/*
 * -o with --voronoi: one cell per line, for each distinct point in input
 * order of its first occurrence, its ring counter-clockwise and not closed.
 */
static void
write_cells(const char *outpath, const oneshot *r)
{
	FILE	   *f = open_output(outpath);
	unsigned char *seen = calloc(tdc_site_id_limit(r->job) + 1, 1);
	g17_line	l;

	if (f == NULL || seen == NULL)
		die(1, "cannot write %s", outpath);
	for (size_t i = 0; i < tdc_num_input(r->job); i++)
	{
		uint32_t	s = tdc_input_site(r->job, i);
		const double *c;
		size_t		m;

		if (s == UINT32_MAX)
			die(1, "out of memory%s", "");
		if (seen[s])
			continue;
		seen[s] = 1;
		m = tdc_voronoi_cell(r->vor, s, &c);
		g17_line_start(&l, f);
		for (size_t k = 0; k < 2 * m; k++)
			g17_line_num(&l, c[k]);
		g17_line_end(&l);
	}
	free(seen);
	if (f != stdout && fclose(f) != 0)
		die(1, "error writing %s", outpath);
}

/* -o: one triangle per line, counter-clockwise, z beside x y when given */
static void
write_triangles(const char *outpath, const double *z, const tdc_job *job)
{
	FILE	   *f = open_output(outpath);
	tdc_iter	it = {0};
	uint32_t	v[3];
	g17_line	l;

	if (f == NULL)
		die(1, "cannot write %s", outpath);
	while (tdc_next_triangle(job, &it, v))
	{
		g17_line_start(&l, f);
		for (int k = 0; k < 3; k++)
		{
			const double *p = tdc_site_xy(job, v[k]);

			g17_line_num(&l, p[0]);
			g17_line_num(&l, p[1]);
			if (z)
				g17_line_num(&l, z[tdc_site_input(job, v[k])]);
		}
		g17_line_end(&l);
	}
	if (f != stdout && fclose(f) != 0)
		die(1, "error writing %s", outpath);
}

/* The output: -o, cells with --voronoi, else triangles. */
void
oneshot_write(const cli_args *a, const cli_input *in, const oneshot *r)
{
	if (a->outpath && r->vor)
		write_cells(a->outpath, r);
	else if (a->outpath)
		write_triangles(a->outpath, in->z, r->job);
}

/* --stats lines, then --validate (exit 1 when invalid). */
void
oneshot_report(const cli_args *a, const oneshot *r)
{
	char		err[512];

	if (a->stats)
	{
		tdc_times	t;
		struct rusage ru;

		tdc_job_times(r->job, &t);
		getrusage(RUSAGE_SELF, &ru);
		fprintf(stderr,
				"n=%zu unique=%zu triangles=%zu threads=%d sort=%.6f subdivide=%.6f leaves=%.6f merge=%.6f total=%.6f peak_rss_mb=%.1f%s\n",
				tdc_num_input(r->job), tdc_num_sites(r->job), tdc_num_triangles(r->job),
				tdc_threads_used(r->job), t.sort, t.subdivide, t.leaves, t.merge, t.total,
				ru.ru_maxrss / 1024.0, a->max_mb > 0 ? " tiles=1 halo_points=0 tile_runs=1" : "");
		if (r->vor)
			fprintf(stderr, "voronoi=%.6f cell_vertices=%zu\n", r->vor_seconds,
					tdc_voronoi_num_vertices(r->vor));
		if (r->cdt)
		{
			size_t		par,
						def,
						ser;

			tdc_cdt_pass_counts(r->cdt, &par, &def, &ser);
			fprintf(stderr, "segments=%zu constraint_edges=%zu constrain=%.6f parallel=%zu deferred=%zu two_stripes=%zu\n",
					r->nseg, tdc_cdt_num_constraint_edges(r->cdt), r->constrain_s, par, def, ser);
		}
	}
	if (a->validate)
	{
		if ((r->cdt ? tdc_cdt_validate(r->cdt, err, sizeof(err)) :
			 tdc_validate_job(r->job, err, sizeof(err))) != 0)
		{
			tdc_job_free(r->job);
			die(1, "INVALID triangulation: %s", err);
		}
		fprintf(stderr, "valid: %zu sites, %zu triangles%s, checked exactly\n",
				tdc_num_sites(r->job), tdc_num_triangles(r->job),
				r->cdt ? ", constrained Delaunay" : "");
	}
}

void
oneshot_free(oneshot *r, cli_input *in)
{
	tdc_voronoi_free(r->vor);
	free(r->cells);
	tdc_cdt_free(r->cdt);
	tdc_job_free(r->job);
	free(r->seg);
	free(in->xy);
	free(in->z);
	free(in->srs);
}
