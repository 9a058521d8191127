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
 * (or - for stdin) of text lines "x y" or "x y z"; beyond the fixed
 * interface, a .xyz.bin file of float64 x,y,z triples, or a LAS file (.las,
 * las.c), whose points --class LIST keeps to those of the listed
 * classification values.  -o writes one triangle
 * per line, counter-clockwise, each vertex "x y" (plus z when the input had
 * z), %.17g.  --stats prints one line of counts and phase times to stderr.
 * This interface is fixed: scripts depend on it.
 *
 * --max-memory MB [--tmpdir DIR] runs here as usual when the one-shot run
 * fits; otherwise the core's tdc_bounded_run (src/core/tiles/bounded*.c, called
 * from tiles.c) triangulates the input tile by tile through files.
 *
 * --contours INTERVAL [--base B] and --grid CELLSIZE [--extent X0,Y0,X1,Y1]
 * [--method M]: the TIN of 'x y z' input, its contour lines or a grid of
 * its heights (tin_out.c, which says the formats), written to -o instead
 * of the triangles.  A grid's -o ending in .tif is a GeoTIFF (geotiff.c)
 * with the CRS of --srs SRS (checked by GDAL here, before any work) or the
 * input's, Float64 or --type Float32.  --grid with --segments FILE and --method
 * linear:breaklines=true grids the TIN of the constrained triangulation
 * (the segments are breaklines); either without the other is an error.
 * --contours takes --method too, linear with max_edge only (the one method
 * parser, tdc_interp_parse: the lines stop at the triangles it drops).
 * --grid with --max-memory, when the one-shot run (the TIN and the grid's
 * values included) does not fit, rasterises the tiles' final triangles as
 * they come (grid_tiles.c): the same pixels, linear only; --contours
 * likewise cuts them into pieces of lines, joined after the last tile
 * (contours_tiles.c): the same lines.
 *
 * main: the arguments (parse_args), the input (read_input, or for
 * --max-memory stage_input, then read_staged when the one-shot run fits),
 * the run and its output (oneshot.c, or run_in_tiles).
 */
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>

#include "cli.h"

static const char usage[] =
"usage: ./tdc [-t THREADS] [-g GRID] [-l LEVELS] [--tolerance T] [-o OUT] [--stats] [--validate]\n"
"             [--voronoi] [--segments FILE] [--max-memory MB [--tmpdir DIR]]\n"
"             [--contours INTERVAL [--base B] [--method linear:max_edge=L]]\n"
"             [--grid CELLSIZE [--extent X0,Y0,X1,Y1] [--method M] [--srs SRS] [--type T]]\n"
"             [--class LIST] INPUT\n"
"  INPUT  .bin file of little-endian float64 x,y pairs, .xyz.bin file of\n"
"         float64 x,y,z triples, a LAS file (.las: LAS 1.2 to 1.4,\n"
"         uncompressed, point formats 0 to 10; x y z with the header's scale\n"
"         and offset), or a text file of 'x y' or 'x y z' lines ('-' reads stdin)\n"
"  --class LIST  LAS input: keep the points of these classification values\n"
"         (comma-separated, 0 to 255: 2 ground, 2,9 ground and water)\n"
"  -t     worker threads (0 = all online CPUs, the default)\n"
"  -g     auxiliary grid size s (0 = auto)\n"
"  -l     subdivision levels d, 2^d subsets (0 = auto, -1 = none)\n"
"  --tolerance T  drop sites closer than T to an already kept site\n"
"  -o     write triangles, one per line, counter-clockwise, %.17g\n"
"  --stats  print counts and phase times (seconds) to stderr; LAS input first\n"
"         adds 'las=VERSION format= points= kept= srs=' (its CRS, or none)\n"
"  --validate  check the result with the exact validator; exit 1 if invalid\n"
"  --voronoi  also build the Voronoi cells; -o writes cells, one ring per line\n"
"  --max-memory MB  keep the peak memory under MB: when the one-shot run does\n"
"         not fit, triangulate in tiles on disk (same triangles, another order)\n"
"  --tmpdir DIR  where the tiles go (default $TMPDIR or /tmp)\n"
"  --segments FILE  constraint segments, lines 'i j' of 0-based INPUT point\n"
"         indices: the constrained Delaunay triangulation; crossing segments\n"
"         are an error (exit 1)\n"
"  --contours INTERVAL  contour lines of the TIN of 'x y z' input at levels\n"
"         B + k INTERVAL (--base B, default 0); -o writes one per line:\n"
"         the level, then 'x y' pairs (a closed ring repeats its first point);\n"
"         --method linear:max_edge=L: lines stop at triangles max_edge drops;\n"
"         with --max-memory, when it does not fit, in tiles: the same lines\n"
"  --grid CELLSIZE  heights at the pixel centres of a grid of square cells\n"
"         over the input's box (or --extent X0,Y0,X1,Y1), from its lower left\n"
"         corner; -o writes an ESRI ASCII grid (.asc), or a GeoTIFF when it\n"
"         ends in .tif (tiled 256x256, DEFLATE, floating-point predictor, the\n"
"         method's nodata; GDAL's georeferencing: origin at the upper left\n"
"         corner, values at the pixel centres, as gdal_grid's);\n"
"         --method linear|nearest|natural_neighbor with\n"
"         GDAL's options (e.g. linear:radius=0:nodata=-9999; default linear);\n"
"         with --segments FILE and --method linear:breaklines=true the\n"
"         segments are breaklines: the TIN is the constrained triangulation;\n"
"         with --max-memory, when it does not fit, in tiles (linear only):\n"
"         the same pixels, the peak under MB\n"
"  --srs SRS  the GeoTIFF's CRS, anything GDAL's SetFromUserInput takes\n"
"         (EPSG:25832, WKT, a PROJ string); default the input's, else none\n"
"  --type Float64|Float32  the GeoTIFF's values: Float64 (default, the\n"
"         .asc's values exactly) or Float32 (half the size, rounded)\n"
"  max_edge=L  (any method) a triangle with an edge longer than L, in x and\n"
"         y, is dropped: no value strictly inside it (nodata), no contour\n"
"         across it; an edge exactly L long is kept, a sample keeps its\n"
"         height, a point on an edge of a kept triangle has a value\n";

static double
parse_double(const char *s, const char *what)
{
	char	   *end;
	double		v;

	errno = 0;
	v = strtod(s, &end);
	if (errno || *s == '\0' || *end != '\0' || !isfinite(v))
		die(2, "invalid value for %s", what);
	return v;
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

/*
 * The command line into a; dies (exit 2) on a bad one.  False after
 * printing the help: nothing more to do.
 */
static bool
parse_args(int argc, char **argv, cli_args *a)
{
	bool		has_type = false;

	memset(a, 0, sizeof(*a));
	tdc_options_init(&a->opt);
	a->opt.times = 1;
	for (int i = 1; i < argc; i++)
	{
		const char *s = argv[i];

		if (strcmp(s, "-h") == 0 || strcmp(s, "--help") == 0)
		{
			fputs(usage, stdout);
			return false;
		}
		else if (strcmp(s, "--stats") == 0)
			a->stats = 1;
		else if (strcmp(s, "--validate") == 0)
			a->validate = 1;
		else if (strcmp(s, "--voronoi") == 0)
			a->voronoi = 1;
		else if (strcmp(s, "--max-memory") == 0 || strcmp(s, "--tmpdir") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			if (s[2] == 'm')
			{
				a->max_mb = parse_int(argv[++i], "--max-memory");
				if (a->max_mb <= 0)
					die(2, "invalid value for %s", "--max-memory");
			}
			else
				a->tmpdir = argv[++i];
		}
		else if (strcmp(s, "--segments") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			a->segpath = argv[++i];
		}
		else if (strcmp(s, "--contours") == 0 || strcmp(s, "--base") == 0 ||
				 strcmp(s, "--grid") == 0)
		{
			double		v;

			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			v = parse_double(argv[++i], s);
			if (strcmp(s, "--base") == 0)
				a->contour_base = v;
			else if (!(v > 0) || isinf(v))
				die(2, "%s must be a finite number > 0", s);
			else if (s[2] == 'c')
				a->contours = 1, a->contour_interval = v;
			else
				a->grid = 1, a->grid_cell = v;
		}
		else if (strcmp(s, "--extent") == 0)
		{
			char	   *p,
					   *end;

			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			p = argv[++i];
			for (int k = 0; k < 4; k++)
			{
				errno = 0;
				a->extent[k] = strtod(p, &end);
				if (end == p || errno || !isfinite(a->extent[k]) || (k < 3 ? *end != ',' : *end != '\0'))
					die(2, "invalid value for %s (XMIN,YMIN,XMAX,YMAX)", "--extent");
				p = end + 1;
			}
			if (!(a->extent[0] < a->extent[2] && a->extent[1] < a->extent[3]))
				die(2, "--extent: XMIN < XMAX and YMIN < YMAX%s", "");
			a->has_extent = 1;
		}
		else if (strcmp(s, "--class") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			las_parse_classes(argv[++i], a->class_keep);
			a->has_class = 1;
		}
		else if (strcmp(s, "--method") == 0 || strcmp(s, "--srs") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			if (s[2] == 'm')
				a->method = argv[++i];
			else
				a->srs = argv[++i];
		}
		else if (strcmp(s, "--type") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			if (strcasecmp(argv[++i], "Float32") == 0)
				a->float32 = 1;
			else if (strcasecmp(argv[i], "Float64") == 0)
				a->float32 = 0;
			else
				die(2, "--type: Float64 or Float32, not %s", argv[i]);
			has_type = true;
		}
		else if (strcmp(s, "-t") == 0 || strcmp(s, "-g") == 0 || strcmp(s, "-l") == 0 ||
				 strcmp(s, "-o") == 0 || strcmp(s, "--tolerance") == 0)
		{
			if (i + 1 >= argc)
				die(2, "option %s needs a value", s);
			if (s[1] == 't')
				a->opt.threads = (int) parse_int(argv[++i], "-t");
			else if (s[1] == 'g')
				a->opt.grid_size = (int) parse_int(argv[++i], "-g");
			else if (s[1] == 'l')
				a->opt.levels = (int) parse_int(argv[++i], "-l");
			else if (s[1] == 'o')
				a->outpath = argv[++i];
			else
			{
				char	   *end;

				a->opt.tolerance = strtod(argv[++i], &end);
				if (*argv[i] == '\0' || *end != '\0')
					die(2, "invalid value for %s", "--tolerance");
			}
		}
		else if (s[0] == '-' && s[1] != '\0')
			die(2, "unknown option %s (see ./tdc --help)", s);
		else if (a->input)
			die(2, "more than one INPUT given: %s", s);
		else
			a->input = s;
	}
	if (a->input == NULL)
		die(2, "no INPUT given (see ./tdc --help)%s", "");
	if (a->has_class && !is_las_path(a->input))
		die(2, "--class goes with LAS input (a name ending in .las): %s", a->input);
	if (a->contours && a->grid)
		die(2, "--contours and --grid: one at a time%s", "");
	if ((a->contours || a->grid) && a->voronoi)
		die(2, "--contours and --grid take the Delaunay TIN: not with --voronoi%s", "");
	if (a->contours && a->segpath)
		die(2, "--contours takes the Delaunay TIN: not with --segments%s", "");
	if (a->has_extent && !a->grid)
		die(2, "--extent goes with --grid%s", "");
	if (a->method && !a->grid && !a->contours)
		die(2, "--method goes with --grid or --contours%s", "");
	if (a->contour_base != 0 && !a->contours)
		die(2, "--base goes with --contours%s", "");
	if (a->grid)
	{
		tdc_interp_spec spec;
		char		err[256];

		if (tdc_interp_parse(a->method ? a->method : "linear", &spec, err, sizeof(err)) != TDC_OK)
			die(2, "--method: %s", err);
		/* the breaklines are the segments: one without the other is a mistake */
		if (spec.breaklines && !a->segpath)
			die(2, "--method with breaklines=true needs the breaklines: --segments FILE%s", "");
		if (a->segpath && !spec.breaklines)
			die(2, "--grid with --segments takes them as breaklines: --method linear:breaklines=true%s", "");
		if (a->float32 && (double) (float) spec.nodata != spec.nodata)
			die(2, "--type Float32: the method's nodata is not a Float32 value (%s)",
				a->method ? a->method : "linear");
	}
	if (gtiff_path(a->outpath) && !a->grid)
		die(2, "-o %s: a GeoTIFF holds a --grid; the other outputs are text", a->outpath);
	if ((a->srs || has_type) && !(a->grid && gtiff_path(a->outpath)))
		die(2, "--srs and --type go with --grid and an -o ending in .tif%s", "");
	if (a->srs)
	{
		char		err[1024];

		if (gtiff_check_srs(a->srs, err, sizeof(err)) != 0)
			die(2, "--srs: %s", err);
	}
	if (a->contours && a->method)
	{
		tdc_interp_spec spec;
		char		err[256];

		if (tdc_interp_parse(a->method, &spec, err, sizeof(err)) != TDC_OK ||
			tdc_tin_contours_spec_check(&spec, err, sizeof(err)) != TDC_OK)
			die(2, "--method: %s", err);
	}
	return true;
}

/* The input of --max-memory as a .bin file (z beside it), sized; a LAS file's CRS */
typedef struct staged
{
	char		xypath[4400],
				zpath[4400];
	int			has_z;
	size_t		n;
	char	   *srs;
} staged;

/*
 * --max-memory: the input as a .bin source: a .bin INPUT as it is, text,
 * LAS and .xyz.bin converted to a temporary .bin (z beside it) on the way,
 * so that they are never held whole.  Makes the temporary directory,
 * removed at exit.
 */
static void
stage_input(const cli_args *a, staged *s)
{
	const char *base = a->tmpdir ? a->tmpdir : getenv("TMPDIR") ? getenv("TMPDIR") : "/tmp";
	struct stat sb;

	s->has_z = 0;
	s->srs = NULL;
	tmp_create(base);
	if (is_las_path(a->input) || is_xyz_bin_path(a->input))
	{
		s->n = is_las_path(a->input) ? las_to_bin(a, &s->srs) : xyz_bin_to_bin(a->input);
		s->has_z = 1;
		snprintf(s->xypath, sizeof(s->xypath), "%s/input.xy", tmp_dir);
		snprintf(s->zpath, sizeof(s->zpath), "%s/input.z", tmp_dir);
	}
	else if (is_bin_path(a->input))
	{
		if (stat(a->input, &sb) != 0)
			die(1, "cannot open %s", a->input);
		if (sb.st_size % 16 != 0)
			die(1, "%s: size is not a multiple of 16 bytes (x,y float64 pairs)", a->input);
		s->n = (size_t) sb.st_size / 16;
		snprintf(s->xypath, sizeof(s->xypath), "%s", a->input);
	}
	else
	{
		s->n = text_to_bin(a->input, &s->has_z);
		snprintf(s->xypath, sizeof(s->xypath), "%s/input.xy", tmp_dir);
		snprintf(s->zpath, sizeof(s->zpath), "%s/input.z", tmp_dir);
	}
}

/* The box of the staged points (they fit in memory: read in chunks all the same). */
static void
staged_box(const staged *s, double box[4])
{
	FILE	   *f = fopen(s->xypath, "rb");
	double		buf[2 * 4096];
	size_t		k;
	bool		any = false;

	if (f == NULL)
		die(1, "cannot open %s", s->xypath);
	while ((k = fread(buf, 16, 4096, f)) > 0)
		for (size_t i = 0; i < k; i++)
		{
			double		x = buf[2 * i],
						y = buf[2 * i + 1];

			if (!any)
			{
				box[0] = box[2] = x;
				box[1] = box[3] = y;
				any = true;
			}
			box[0] = x < box[0] ? x : box[0];
			box[2] = x > box[2] ? x : box[2];
			box[1] = y < box[1] ? y : box[1];
			box[3] = y > box[3] ? y : box[3];
		}
	fclose(f);
}

/*
 * Whether the one-shot run of the staged input fits in --max-memory: the
 * engine, the input, what the process holds now (at least 8 MB; GDAL's
 * libraries when a GeoTIFF is to be written, loaded by then) and, for a
 * GeoTIFF, GDAL's block cache.
 */
static bool
fits(const cli_args *a, const staged *s, bool tif)
{
	size_t		budget = (size_t) a->max_mb << 20,
				base = heap_resident(),
				need;

	if (base < ((size_t) 8 << 20))
		base = (size_t) 8 << 20;
	need = tdc_estimate_memory(s->n, &a->opt) + s->n * (16 + (s->has_z ? 12 : 0)) + base +
		(tif ? GTIFF_HOLD(a->opt.threads) : 0);
	if (need > budget)
		return false;
	if (a->contours)
		need += tdc_tin_memory(s->n);	/* the TIN; the lines are charged as they come */
	if (a->grid)
	{
		/* the TIN, and the grid's values and flags (9 bytes a pixel) over the extent or the box */
		tdc_grid_spec g;
		double		data_box[4] = {0, 0, 0, 0},
					box[4];
		char		err[256];

		if (!a->has_extent)
			staged_box(s, data_box);
		need += tdc_tin_memory(s->n);
		if (grid_geometry(a, data_box, &g, box, err, sizeof(err)) != 0)
			die(1, "%s", err);
		need += 9 * g.width * g.height;
	}
	return need <= budget;
}

/*
 * The staged input triangulated tile by tile (tiles.c), the triangles
 * to -o, the --stats line.  The options that need the whole triangulation
 * in memory are refused.
 */
static void
run_in_tiles(const cli_args *a, const staged *s, gtiff_out *tif)
{
	tdc_bounded_stats st;
	FILE	   *f = NULL;
	struct timespec t0,
				t1;

	if (a->opt.tolerance > 0)
		die(1, "--tolerance cannot be used when the input must be tiled (%s)", "which points are merged depends on all of them");
	if (a->validate)
		die(1, "--validate needs the whole triangulation in memory; %s", "raise --max-memory");
	if (a->voronoi)
		die(1, "--voronoi needs the whole triangulation in memory; %s", "raise --max-memory");
	if (a->segpath)
		die(1, "--segments needs the whole triangulation in memory; %s", "raise --max-memory");
	if (a->contours)
	{
		contours_in_tiles(a, s->xypath, s->has_z ? s->zpath : NULL, s->n);
		return;
	}
	if (a->grid)
	{
		grid_in_tiles(a, s->xypath, s->has_z ? s->zpath : NULL, s->n, a->srs ? a->srs : s->srs, tif);
		return;
	}
	if (a->outpath)
	{
		f = strcmp(a->outpath, "-") == 0 ? stdout : fopen(a->outpath, "w");
		if (f == NULL)
			die(1, "cannot write %s", a->outpath);
	}
	clock_gettime(CLOCK_MONOTONIC, &t0);
	run_bounded(s->xypath, s->has_z ? s->zpath : NULL, s->n, &a->opt,
				(size_t) a->max_mb << 20, f, &st);
	clock_gettime(CLOCK_MONOTONIC, &t1);
	if (f && f != stdout && fclose(f) != 0)
		die(1, "error writing %s", a->outpath);
	if (a->stats)
	{
		struct rusage ru;

		getrusage(RUSAGE_SELF, &ru);
		fprintf(stderr,
				"n=%zu unique=%zu triangles=%zu threads=%d sort=%.6f subdivide=%.6f leaves=%.6f merge=%.6f total=%.6f peak_rss_mb=%.1f tiles=%d halo_points=%zu tile_runs=%zu reread_points=%zu scan=%.6f bin=%.6f gather=%.6f engine=%.6f finish=%.6f write=%.6f workers=%d wait=%.6f tiles_wall=%.6f bin_threads=%d\n",
				st.n, st.unique, st.ntri, st.threads, st.t.sort, st.t.subdivide,
				st.t.leaves, st.t.merge,
				(t1.tv_sec - t0.tv_sec) + (t1.tv_nsec - t0.tv_nsec) * 1e-9,
				ru.ru_maxrss / 1024.0, st.tiles, st.halo, st.runs, st.reread,
				st.scan, st.bin, st.gather, st.engine, st.finish, st.write, st.workers, st.wait, st.tiles_wall, st.bin_threads);
	}
}

/* The staged input into memory, for the one-shot run; the temporary files removed. */
static void
read_staged(const staged *s, cli_input *in)
{
	in->xy = read_bin(s->xypath, &in->n);
	in->z = NULL;
	in->srs = s->srs;
	if (s->has_z)
	{
		FILE	   *fz = fopen(s->zpath, "rb");

		in->z = malloc(8 * in->n + 8);
		if (fz == NULL || in->z == NULL || fread(in->z, 8, in->n, fz) != in->n)
			die(1, "cannot read the temporary z file in %s", tmp_dir);
		fclose(fz);
	}
	tmp_cleanup();
	if (cli_cancel)
		raise(cli_cancel);		/* it came while the input was staged */
}

/*
 * A bounded run bins its input on two threads when it may hold two sets of
 * tile files open (bounded_bin.c reads the soft limit): a shell's soft
 * limit is often 1,024 where the hard one is far higher, so raise it, as
 * far as the hard limit allows.  Nothing else changes if it cannot.
 */
static void
raise_open_files(void)
{
	struct rlimit rl;

	if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < rl.rlim_max)
	{
		rl.rlim_cur = rl.rlim_max == RLIM_INFINITY || rl.rlim_max > 65536 ? 65536 : rl.rlim_max;
		(void) setrlimit(RLIMIT_NOFILE, &rl);
	}
}

int
main(int argc, char **argv)
{
	cli_args	a;
	cli_input	in = {0};
	oneshot		r;
	gtiff_out  *tif;

	if (!parse_args(argc, argv, &a))
		return 0;
	if (a.max_mb > 0)
	{
		staged		s;

		raise_open_files();
		stage_input(&a, &s);
		/* a grid's GeoTIFF: GDAL loaded now, so that the limit counts it */
		in.n = s.n;
		in.srs = s.srs;
		tif = tin_output_prepare(&a, &in);
		if (!fits(&a, &s, tif != NULL))
		{
			run_in_tiles(&a, &s, tif);
			free(s.srs);
			return 0;
		}
		read_staged(&s, &in);
	}
	else
	{
		read_input(&a, &in);
		tif = tin_output_prepare(&a, &in);
	}
	oneshot_run(&a, &in, &r);
	if (a.contours || a.grid)
		tin_output(&a, &in, &r, tif);
	else
		oneshot_write(&a, &in, &r);
	oneshot_report(&a, &r);
	oneshot_free(&r, &in);
	return 0;
}
