/*
 * tdc.c
 *		./tdc: the command-line front end of the core.
 *
 *	./tdc [-t THREADS] [-g GRID] [-l LEVELS] [--tolerance T] [-o OUT] [--stats] INPUT
 *
 * and, beyond the fixed interface, --validate: check the result with the
 * exact validator (slow, and about 60 more bytes per point), and --voronoi:
 * build the Voronoi cells too, clipped to GEOS's default envelope (the
 * input's box grown by its larger side); -o then writes one cell per line,
 * for each distinct point in input order of its first occurrence, its ring
 * counter-clockwise and not closed, "x y" per vertex, %.17g; --stats adds a
 * line with the Voronoi time (without -o: sizing the cells and writing them
 * into one buffer, as the extension does); and --segments FILE: constraint segments, one
 * per line "i j", two 0-based line numbers (point indices) of INPUT; the
 * result is then the constrained Delaunay triangulation (cdt.c), and with
 * --stats a second line "segments= constraint_edges= constrain= parallel= deferred=
 * two_stripes=" follows (the last three: tdc_cdt_pass_counts).
 *
 * INPUT is a .bin file of little-endian float64 x,y pairs, or any other file
 * (or - for stdin) of text lines "x y" or "x y z".  -o writes one triangle
 * per line, counter-clockwise, each vertex "x y" (plus z when the input had
 * z), %.17g.  --stats prints one line of counts and phase times to stderr.
 * This interface is fixed: scripts depend on it.
 *
 * --max-memory MB [--tmpdir DIR] runs here as usual when the one-shot run
 * fits; otherwise tiled.c triangulates the input tile by tile through files.
 */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <stdbool.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>

#include "cli.h"

static const char usage[] =
"usage: ./tdc [-t THREADS] [-g GRID] [-l LEVELS] [--tolerance T] [-o OUT] [--stats] [--validate]\n"
"             [--voronoi] [--segments FILE] [--max-memory MB [--tmpdir DIR]] INPUT\n"
"  INPUT  .bin file of little-endian float64 x,y pairs, or a text file of\n"
"         'x y' or 'x y z' lines ('-' reads stdin)\n"
"  -t     worker threads (0 = all online CPUs, the default)\n"
"  -g     auxiliary grid size s (0 = auto)\n"
"  -l     subdivision levels d, 2^d subsets (0 = auto, -1 = none)\n"
"  --tolerance T  drop sites closer than T to an already kept site\n"
"  -o     write triangles, one per line, counter-clockwise, %.17g\n"
"  --stats  print counts and phase times (seconds) to stderr\n"
"  --validate  check the result with the exact validator; exit 1 if invalid\n"
"  --voronoi  also build the Voronoi cells; -o writes cells, one ring per line\n"
"  --max-memory MB  keep the peak memory under MB: when the one-shot run does\n"
"         not fit, triangulate in tiles on disk (same triangles, another order)\n"
"  --tmpdir DIR  where the tiles go (default $TMPDIR or /tmp)\n"
"  --segments FILE  constraint segments, lines 'i j' of 0-based INPUT point\n"
"         indices: the constrained Delaunay triangulation; crossing segments\n"
"         are an error (exit 1)\n";

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

void
die(int code, const char *fmt, const char *arg)
{
	fprintf(stderr, "tdc: ");
	fprintf(stderr, fmt, arg);
	fputc('\n', stderr);
	exit(code);
}

static long
parse_int(const char *s, const char *what)
{
	char	   *end;
	long		v;

	errno = 0;
	v = strtol(s, &end, 10);
	if (errno || *s == '\0' || *end != '\0')
		die(2, "invalid value for %s", what);
	return v;
}

static int
ends_with(const char *s, const char *suffix)
{
	size_t		a = strlen(s),
				b = strlen(suffix);

	return a >= b && strcmp(s + a - b, suffix) == 0;
}

static double *
read_bin(const char *path, size_t *n)
{
	FILE	   *f = fopen(path, "rb");
	long		size;
	double	   *xy;

	if (f == NULL)
		die(1, "cannot open %s", path);
	if (fseek(f, 0, SEEK_END) != 0 || (size = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0)
		die(1, "cannot read %s", path);
	if (size % 16 != 0)
		die(1, "%s: size is not a multiple of 16 bytes (x,y float64 pairs)", path);
	*n = (size_t) size / 16;
	xy = malloc((size_t) size + 16);
	if (xy == NULL)
		die(1, "out of memory reading %s", path);
	if (fread(xy, 16, *n, f) != *n)
		die(1, "short read on %s", path);
	fclose(f);
	return xy;
}

/*
 * Parse one text line into v: returns the number of values (0 for a blank
 * or comment line), dies on garbage.  *dims is the line width seen so far.
 */
int
parse_line(char *line, size_t lineno, double v[3], int *dims)
{
	int			k = 0;
	char	   *p = line,
			   *end;

	while (k < 4)
	{
		while (*p == ' ' || *p == '\t' || *p == ',' || *p == '\r' || *p == '\n')
			p++;
		if (*p == '\0' || *p == '#')
			break;
		if (k == 3)
		{
			k = 4;
			break;
		}
		v[k] = strtod(p, &end);
		if (end == p)
		{
			char		msg[64];

			snprintf(msg, sizeof(msg), "%zu", lineno);
			die(1, "line %s: expected numbers 'x y' or 'x y z'", msg);
		}
		p = end;
		k++;
	}
	if (k == 0)
		return 0;
	if (k == 1 || k == 4 || (*dims && k != *dims))
	{
		char		msg[64];

		snprintf(msg, sizeof(msg), "%zu", lineno);
		die(1, "line %s: every line must hold 'x y' or every line 'x y z'", msg);
	}
	*dims = k;
	return k;
}

static double *
read_text(const char *path, size_t *n, double **zout)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
	char	   *line = NULL;
	size_t		cap = 0,
				alloc = 1024,
				lineno = 0;
	int			dims = 0;
	double	   *xy = malloc(alloc * 2 * sizeof(double)),
			   *z = NULL;

	if (f == NULL)
		die(1, "cannot open %s", path);
	*n = 0;
	while (getline(&line, &cap, f) >= 0)
	{
		double		v[3];

		if (parse_line(line, ++lineno, v, &dims) == 0)
			continue;
		if (*n == alloc)
		{
			alloc *= 2;
			xy = realloc(xy, alloc * 2 * sizeof(double));
			if (dims == 3)
				z = realloc(z, alloc * sizeof(double));
		}
		if (dims == 3 && z == NULL)
			z = malloc(alloc * sizeof(double));
		if (xy == NULL || (dims == 3 && z == NULL))
			die(1, "out of memory reading %s", path);
		xy[2 * *n] = v[0];
		xy[2 * *n + 1] = v[1];
		if (dims == 3)
			z[*n] = v[2];
		(*n)++;
	}
	free(line);
	if (f != stdin)
		fclose(f);
	*zout = z;
	return xy;
}

/* Segment file: lines "i j"; every index must be below n. */
static uint32_t *
read_segments(const char *path, size_t n, size_t *k)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "r");
	size_t		cap = 1024;
	uint32_t   *seg = malloc(cap * 2 * sizeof(uint32_t));
	unsigned long long a,
				b;
	int			got;

	if (f == NULL)
		die(1, "cannot read %s", path);
	if (seg == NULL)
		die(1, "out of memory for %s", path);
	*k = 0;
	while ((got = fscanf(f, "%llu %llu", &a, &b)) == 2)
	{
		if (a >= n || b >= n)
			die(1, "segment index beyond the input's points in %s", path);
		if (*k == cap)
		{
			seg = realloc(seg, (cap *= 2) * 2 * sizeof(uint32_t));
			if (seg == NULL)
				die(1, "out of memory for %s", path);
		}
		seg[2 * *k] = (uint32_t) a;
		seg[2 * *k + 1] = (uint32_t) b;
		(*k)++;
	}
	if (got != EOF)
		die(1, "%s: lines must be two point indices 'i j'", path);
	if (f != stdin)
		fclose(f);
	return seg;
}

int
main(int argc, char **argv)
{
	tdc_options opt;
	const char *input = NULL,
			   *outpath = NULL;
	int			stats = 0,
				validate = 0,
				voronoi = 0,
				rc;
	tdc_voronoi *vor = NULL;
	char	   *cells = NULL;
	double		vor_seconds = 0;
	size_t		n;
	double	   *xy,
			   *z = NULL;
	tdc_job    *job;
	tdc_cdt    *cdt = NULL;
	const char *segpath = NULL;
	uint32_t   *seg = NULL;
	size_t		nseg = 0;
	double		constrain_s = 0;
	char		err[512];
	long		max_mb = 0;
	const char *tmpdir = NULL;

	tdc_options_init(&opt);
	opt.times = 1;
	for (int i = 1; i < argc; i++)
	{
		const char *a = argv[i];

		if (strcmp(a, "-h") == 0 || strcmp(a, "--help") == 0)
		{
			fputs(usage, stdout);
			return 0;
		}
		else if (strcmp(a, "--stats") == 0)
			stats = 1;
		else if (strcmp(a, "--validate") == 0)
			validate = 1;
		else if (strcmp(a, "--voronoi") == 0)
			voronoi = 1;
		else if (strcmp(a, "--max-memory") == 0 || strcmp(a, "--tmpdir") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", a);
			if (a[2] == 'm')
			{
				max_mb = parse_int(argv[++i], "--max-memory");
				if (max_mb <= 0)
					die(2, "invalid value for %s", "--max-memory");
			}
			else
				tmpdir = argv[++i];
		}
		else if (strcmp(a, "--segments") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", a);
			segpath = argv[++i];
		}
		else if (strcmp(a, "-t") == 0 || strcmp(a, "-g") == 0 || strcmp(a, "-l") == 0 ||
				 strcmp(a, "-o") == 0 || strcmp(a, "--tolerance") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", a);
			if (a[1] == 't')
				opt.threads = (int) parse_int(argv[++i], "-t");
			else if (a[1] == 'g')
				opt.grid_size = (int) parse_int(argv[++i], "-g");
			else if (a[1] == 'l')
				opt.levels = (int) parse_int(argv[++i], "-l");
			else if (a[1] == 'o')
				outpath = argv[++i];
			else
			{
				char	   *end;

				opt.tolerance = strtod(argv[++i], &end);
				if (*argv[i] == '\0' || *end != '\0')
					die(2, "invalid value for %s", "--tolerance");
			}
		}
		else if (a[0] == '-' && a[1] != '\0')
			die(2, "unknown option %s (see ./tdc --help)", a);
		else if (input)
			die(2, "more than one INPUT given: %s", a);
		else
			input = a;
	}
	if (input == NULL)
		die(2, "no INPUT given (see ./tdc --help)%s", "");

	if (max_mb > 0)
	{
		/*
		 * Bounded memory: size the one-shot run first (text input goes to a
		 * temporary .bin on the way, so it is never held as text).
		 */
		size_t		budget = (size_t) max_mb << 20,
					need;
		const char *base = tmpdir ? tmpdir : getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
		char		xypath[4400],
					zpath[4400];
		int			has_z = 0;
		struct stat sb;

		snprintf(tmp_dir, sizeof(tmp_dir), "%s/tdc.XXXXXX", base);
		if (mkdtemp(tmp_dir) == NULL)
		{
			tmp_dir[0] = '\0';
			die(1, "cannot create a temporary directory in %s", base);
		}
		atexit(tmp_cleanup);
		if (ends_with(input, ".bin"))
		{
			if (stat(input, &sb) != 0)
				die(1, "cannot open %s", input);
			if (sb.st_size % 16 != 0)
				die(1, "%s: size is not a multiple of 16 bytes (x,y float64 pairs)", input);
			n = (size_t) sb.st_size / 16;
			snprintf(xypath, sizeof(xypath), "%s", input);
		}
		else
		{
			n = text_to_bin(input, &has_z);
			snprintf(xypath, sizeof(xypath), "%s/input.xy", tmp_dir);
			snprintf(zpath, sizeof(zpath), "%s/input.z", tmp_dir);
		}
		need = tdc_estimate_memory(n, &opt) + n * (16 + (has_z ? 12 : 0)) + ((size_t) 8 << 20);
		if (need > budget)
		{
			tiled_stats ts;
			FILE	   *f = NULL;
			struct timespec t0,
						t1;

			if (opt.tolerance > 0)
				die(1, "--tolerance cannot be used when the input must be tiled (%s)", "which points are merged depends on all of them");
			if (validate)
				die(1, "--validate needs the whole triangulation in memory; %s", "raise --max-memory");
			if (voronoi)
				die(1, "--voronoi needs the whole triangulation in memory; %s", "raise --max-memory");
			if (segpath)
				die(1, "--segments needs the whole triangulation in memory; %s", "raise --max-memory");
			if (outpath)
			{
				f = strcmp(outpath, "-") == 0 ? stdout : fopen(outpath, "w");
				if (f == NULL)
					die(1, "cannot write %s", outpath);
			}
			clock_gettime(CLOCK_MONOTONIC, &t0);
			run_tiled(xypath, has_z ? zpath : NULL, n, &opt, budget, f, &ts);
			clock_gettime(CLOCK_MONOTONIC, &t1);
			if (f && f != stdout && fclose(f) != 0)
				die(1, "error writing %s", outpath);
			if (stats)
			{
				struct rusage ru;

				getrusage(RUSAGE_SELF, &ru);
				fprintf(stderr,
						"n=%zu unique=%zu triangles=%zu threads=%d sort=%.6f subdivide=%.6f leaves=%.6f merge=%.6f total=%.6f peak_rss_mb=%.1f tiles=%d halo_points=%zu tile_runs=%zu scan=%.6f bin=%.6f gather=%.6f engine=%.6f finish=%.6f write=%.6f\n",
						ts.n, ts.unique, ts.ntri, ts.threads, ts.t.sort, ts.t.subdivide,
						ts.t.leaves, ts.t.merge,
						(t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) * 1e-9,
						ru.ru_maxrss / 1024.0, ts.tiles, ts.halo, ts.runs,
						ts.scan, ts.bin, ts.gather, ts.engine, ts.finish, ts.write);
			}
			return 0;
		}
		/* it fits: run as without the option */
		xy = read_bin(xypath, &n);
		if (has_z)
		{
			FILE	   *fz = fopen(zpath, "rb");

			z = malloc(8 * n + 8);
			if (fz == NULL || z == NULL || fread(z, 8, n, fz) != n)
				die(1, "cannot read the temporary z file in %s", tmp_dir);
			fclose(fz);
		}
		tmp_cleanup();
	}
	else
		xy = ends_with(input, ".bin") ? read_bin(input, &n) : read_text(input, &n, &z);

	rc = tdc_triangulate(xy, n, &opt, &job, err, sizeof(err));
	if (rc != TDC_OK)
	{
		tdc_job_free(job);
		die(1, "%s", err);
	}
	if (segpath && voronoi)
		die(2, "--voronoi of a constrained triangulation is not supported%s", "");
	if (segpath)
	{
		struct timespec t0,
					t1;

		seg = read_segments(segpath, n, &nseg);
		clock_gettime(CLOCK_MONOTONIC, &t0);
		rc = tdc_cdt_run(job, seg, nseg, &cdt, err, sizeof(err));
		clock_gettime(CLOCK_MONOTONIC, &t1);
		constrain_s = (t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) * 1e-9;
		if (rc != TDC_OK)
		{
			tdc_cdt_free(cdt);
			tdc_job_free(job);
			die(1, "%s", err);
		}
	}

	if (voronoi)
	{
		double		env[4];
		struct timespec t0,
					t1;

		clock_gettime(CLOCK_MONOTONIC, &t0);
		tdc_voronoi_default_env(job, env);
		if (outpath)
			rc = tdc_voronoi_build(job, env, opt.threads, &vor, err, sizeof(err));
		else
		{
			/* as the extension does: sized, then written into one buffer */
			tdc_cell_writer w = {cli_cell_size, cli_cell_write, NULL};

			rc = tdc_voronoi_start_emit(job, env, opt.threads, &w, &vor, err, sizeof(err));
			if (rc == TDC_OK)
				rc = tdc_voronoi_wait(vor, -1);
			if (rc == TDC_OK)
			{
				cells = malloc(tdc_voronoi_emit_size(vor, NULL) + 1);
				rc = cells == NULL ? TDC_ENOMEM : tdc_voronoi_emit(vor, cells, err, sizeof(err));
			}
			if (rc == TDC_OK)
				rc = tdc_voronoi_wait(vor, -1);
			if (rc != TDC_OK && vor && !err[0])
				snprintf(err, sizeof(err), "%s", tdc_voronoi_error(vor));
		}
		clock_gettime(CLOCK_MONOTONIC, &t1);
		if (rc != TDC_OK)
		{
			tdc_voronoi_free(vor);
			tdc_job_free(job);
			die(1, "%s", err);
		}
		vor_seconds = (t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) * 1e-9;
	}

	if (outpath && vor)
	{
		FILE	   *f = strcmp(outpath, "-") == 0 ? stdout : fopen(outpath, "w");
		unsigned char *seen = calloc(tdc_site_id_limit(job) + 1, 1);

		if (f == NULL || seen == NULL)
			die(1, "cannot write %s", outpath);
		for (size_t i = 0; i < tdc_num_input(job); i++)
		{
			uint32_t	s = tdc_input_site(job, i);
			const double *c;
			size_t		m;

			if (s == UINT32_MAX)
				die(1, "out of memory%s", "");
			if (seen[s])
				continue;
			seen[s] = 1;
			m = tdc_voronoi_cell(vor, s, &c);
			for (size_t k = 0; k < m; k++)
				fprintf(f, k ? " %.17g %.17g" : "%.17g %.17g", c[2 * k], c[2 * k + 1]);
			fputc('\n', f);
		}
		free(seen);
		if (f != stdout && fclose(f) != 0)
			die(1, "error writing %s", outpath);
	}
	else if (outpath)
	{
		FILE	   *f = strcmp(outpath, "-") == 0 ? stdout : fopen(outpath, "w");
		tdc_iter	it = {0};
		uint32_t	v[3];

		if (f == NULL)
			die(1, "cannot write %s", outpath);
		while (tdc_next_triangle(job, &it, v))
		{
			for (int k = 0; k < 3; k++)
			{
				const double *p = tdc_site_xy(job, v[k]);

				if (z)
					fprintf(f, k ? " %.17g %.17g %.17g" : "%.17g %.17g %.17g", p[0], p[1],
							z[tdc_site_input(job, v[k])]);
				else
					fprintf(f, k ? " %.17g %.17g" : "%.17g %.17g", p[0], p[1]);
			}
			fputc('\n', f);
		}
		if (f != stdout && fclose(f) != 0)
			die(1, "error writing %s", outpath);
	}

	if (stats)
	{
		tdc_times	t;
		struct rusage ru;

		tdc_job_times(job, &t);
		getrusage(RUSAGE_SELF, &ru);
		fprintf(stderr,
				"n=%zu unique=%zu triangles=%zu threads=%d sort=%.6f subdivide=%.6f leaves=%.6f merge=%.6f total=%.6f peak_rss_mb=%.1f%s\n",
				tdc_num_input(job), tdc_num_sites(job), tdc_num_triangles(job),
				tdc_threads_used(job), t.sort, t.subdivide, t.leaves, t.merge, t.total,
				ru.ru_maxrss / 1024.0, max_mb > 0 ? " tiles=1 halo_points=0 tile_runs=1" : "");
		if (vor)
			fprintf(stderr, "voronoi=%.6f cell_vertices=%zu\n", vor_seconds,
					tdc_voronoi_num_vertices(vor));
		if (cdt)
		{
			size_t		par,
						def,
						ser;

			tdc_cdt_pass_counts(cdt, &par, &def, &ser);
			fprintf(stderr, "segments=%zu constraint_edges=%zu constrain=%.6f parallel=%zu deferred=%zu two_stripes=%zu\n",
					nseg, tdc_cdt_num_constraint_edges(cdt), constrain_s, par, def, ser);
		}
	}
	if (validate)
	{
		if ((cdt ? tdc_cdt_validate(cdt, err, sizeof(err)) :
			 tdc_validate_job(job, err, sizeof(err))) != 0)
		{
			tdc_job_free(job);
			die(1, "INVALID triangulation: %s", err);
		}
		fprintf(stderr, "valid: %zu sites, %zu triangles%s, checked exactly\n",
				tdc_num_sites(job), tdc_num_triangles(job),
				cdt ? ", constrained Delaunay" : "");
	}
	tdc_voronoi_free(vor);
	free(cells);
	tdc_cdt_free(cdt);
	tdc_job_free(job);
	free(seg);
	free(xy);
	free(z);
	return 0;
}
