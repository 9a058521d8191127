/*
 * geotiff.c
 *		./tdc --grid to a GeoTIFF (-o ending in .tif or .tiff), through
 *		GDAL's library, the one GIS tools read GeoTIFF with.  Only ./tdc uses
 *		GDAL; the extension's library never does.
 *
 * GDAL is loaded when a GeoTIFF is to be written (dlopen of the library
 * the build compiled against, TDC_GDAL_SONAME), not linked: its library
 * brings some 110 others, and a program that merely links it starts at
 * 31 MB resident instead of 1.3 (26 MB of it library pages, 4.7 MB
 * relocated data and constructors' heap), which --max-memory counts
 * against its limit before the first tile.  So every other run of ./tdc
 * neither needs nor pays for GDAL, and without it a .tif -o is a clear
 * error before any work.  The entry points are resolved by name into
 * pointers of the headers' own types (__typeof__), so the compiler still
 * checks every call against gdal.h.
 *
 * The file: one band, Float64 (the default: the very doubles the .asc
 * grid prints, and gdal_grid's default type) or Float32 (--type Float32:
 * half the size, each value rounded to the nearest float; a value beyond
 * float's range, or a nodata float cannot hold exactly, is an error rather
 * than an infinity or a nodata GDAL would not match), tiled 256 x 256,
 * DEFLATE with the floating-point predictor (PREDICTOR=3), the method's
 * nodata, and BIGTIFF=IF_SAFER: GDAL's IF_NEEDED never makes a BigTIFF
 * when the data is compressed (it cannot know the compressed size), so a
 * grid whose DEFLATE stream passes 4 GiB would fail at that point, while
 * IF_SAFER makes a BigTIFF whenever the uncompressed raster passes about
 * 2 GB (GDAL's threshold, seen at 1.94 GB classic and 2.12 GB BigTIFF):
 * DEFLATE never grows data by more than a few bytes a block, so every
 * classic file it leaves fits.
 *
 * The georeferencing is GDAL's: gt[0], gt[3] is the upper left corner of
 * the upper left pixel, gt[1] the pixel width, gt[5] minus its height,
 * north up, and each value is the one at its pixel's centre (the grid's
 * values are computed there, tdc_tin_grid_start).  gdal_grid's rasters of
 * the same extent and size overlay it exactly.
 *
 * The CRS is a string GDAL's OSRSetFromUserInput takes ("EPSG:25832",
 * WKT, a PROJ string, a file holding one of those); gtiff_check_srs lets
 * the front end refuse a bad one before any work.  Without one the file
 * has none (legal GeoTIFF; the caller warns).
 *
 * Writing.  gtiff_reserve creates the temporary file "OUT.PID.tmp" in
 * OUT's directory at once, so that an unwritable -o fails before the
 * triangulation, not after it.  gtiff_open makes the GeoTIFF there,
 * gtiff_write_rows takes rows top down, in any counts, and gtiff_close
 * renames the file to OUT (replacing it atomically) once GDAL has closed
 * it without error.  Any failure, any exit before the rename (die()
 * included) and SIGINT, SIGTERM or SIGHUP remove the temporary file: no
 * partial .tif is left behind.
 * A sidecar OUT.aux.xml describes the file it sits beside and GDAL reads
 * it before the file's own tags, so a stale one is removed with the file
 * it described; GDAL's own sidecar (a CRS the GeoTIFF keys cannot hold)
 * is renamed with the file.
 *
 * Memory.  Rows that complete a tile row (256 rows, or the last rows) are
 * written straight from the caller's buffer, one tile column at a time,
 * so that each GDAL block is filled whole by one call and compressed once;
 * rows that come in smaller pieces are gathered in a strip buffer of
 * min(256, height) x width doubles, made when first needed.  GDAL's block
 * cache, which holds the blocks until DEFLATE writes them, is capped at
 * GTIFF_CACHE bytes (32 Float64 blocks); libtiff keeps 16 bytes a tile of
 * offsets and sizes, the driver a block's compression buffers.  Loading
 * GDAL itself costs more: a 10 x 10 grid written as .tif peaks at 38 MB
 * resident, 44 MB with --srs EPSG:25832 (PROJ's database), and 16 million
 * pixels at 197 MB against 142 MB as .asc.  GDAL calls are made on the
 * caller's thread only.
 */
#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cpl_error.h>
#include <gdal.h>
#include <gdal_frmts.h>
#include <ogr_srs_api.h>

#include "cli.h"

#ifndef TDC_GDAL_SONAME
#error "TDC_GDAL_SONAME: the soname of the GDAL library compiled against (the Makefile sets it)"
#endif

#define GTIFF_TILE	256
#define GTIFF_CACHE	((GIntBig) GTIFF_CACHE_BYTES)

/* GDAL's entry points used here, loaded by gdal_load */
#define GDAL_ENTRY_POINTS(X) \
	X(CPLErrorReset) X(CPLGetLastErrorMsg) X(CPLGetLastErrorType) X(CPLSetErrorHandler) \
	X(GDALClose) X(GDALCreate) X(GDALGetDriverByName) X(GDALGetRasterBand) \
	X(GDALRasterIOEx) X(GDALRegister_GTiff) X(GDALSetCacheMax64) X(GDALSetGeoTransform) \
	X(GDALSetRasterNoDataValue) X(GDALSetSpatialRef) X(OSRDestroySpatialReference) \
	X(OSRNewSpatialReference) X(OSRSetAxisMappingStrategy) X(OSRSetFromUserInput)

#define GDAL_POINTER(f) __typeof__(f) *f;
static struct
{
	GDAL_ENTRY_POINTS(GDAL_POINTER)
}			gd;

struct gtiff_out
{
	char		path[4096],
				tmp[4200];
	GDALDatasetH ds;
	GDALRasterBandH band;
	size_t		width,
				height,
				next_row;		/* rows written so far (or gathered) */
	bool		float32;
	double	   *strip;			/* rows gathered for a tile row */
	size_t		gathered;
};

/*
 * The temporary file in the making and its possible sidecar, removed at
 * exit, or when SIGINT, SIGTERM or SIGHUP ends the process, unless
 * renamed: the process's one, as tmp_dir is for --max-memory.
 */
static char pending[4200],
			pending_aux[4300];

static void
remove_pending(void)
{
	if (pending[0] == '\0')
		return;
	unlink(pending);
	unlink(pending_aux);
	pending[0] = '\0';
}

/* unlink only (async-signal-safe), then the signal's default action */
static void
remove_pending_signal(int sig)
{
	if (pending[0] != '\0')
	{
		unlink(pending);
		unlink(pending_aux);
	}
	raise(sig);
}

static void
remove_pending_at_exit(void)
{
	static const int sigs[] = {SIGINT, SIGTERM, SIGHUP};
	struct sigaction sa,
				old;

	atexit(remove_pending);
	memset(&sa, 0, sizeof(sa));
	sa.sa_handler = remove_pending_signal;
	sa.sa_flags = SA_RESETHAND | SA_NODEFER;
	sigemptyset(&sa.sa_mask);
	for (int i = 0; i < 3; i++)
		if (sigaction(sigs[i], NULL, &old) == 0 && old.sa_handler == SIG_DFL)
			sigaction(sigs[i], &sa, NULL);
}

/*
 * GDAL's failures are kept for the message of the call that failed
 * (CPLGetLastErrorMsg); its warnings are passed on, marked as GDAL's.
 */
static void
gdal_message(CPLErr level, CPLErrorNum num, const char *msg)
{
	if (level == CE_Warning)
		fprintf(stderr, "tdc: warning: GDAL: %s\n", msg);
}

/*
 * GDAL loaded and set up, once: the GTiff driver, the error handler, the
 * block cache's cap.  -1 with err when its library is missing or lacks
 * an entry point.
 */
static int
gdal_load(char *err, size_t errlen)
{
	static int	state;			/* 0 not tried, 1 loaded, -1 failed */
	static char msg[600];
	void	   *h;

	if (state == 0)
	{
		state = -1;
		if ((h = dlopen(TDC_GDAL_SONAME, RTLD_NOW | RTLD_LOCAL)) == NULL)
			snprintf(msg, sizeof(msg), "a GeoTIFF needs GDAL's library %s (Debian: its package "
					 "libgdalNN): %s", TDC_GDAL_SONAME, dlerror());
#define GDAL_RESOLVE(f) \
		else if ((gd.f = (__typeof__(gd.f)) dlsym(h, #f)) == NULL) \
			snprintf(msg, sizeof(msg), "GDAL's library %s has no %s", TDC_GDAL_SONAME, #f);
		GDAL_ENTRY_POINTS(GDAL_RESOLVE)
		else
		{
			gd.CPLSetErrorHandler(gdal_message);
			gd.GDALRegister_GTiff();
			gd.GDALSetCacheMax64(GTIFF_CACHE);
			state = 1;
		}
	}
	if (state < 0)
		snprintf(err, errlen, "%s", msg);
	return state > 0 ? 0 : -1;
}

/* err := what, then GDAL's last error message if it has one */
static int
fail(char *err, size_t errlen, const char *what, const char *path)
{
	const char *g = gd.CPLGetLastErrorType() >= CE_Failure ? gd.CPLGetLastErrorMsg() : "";

	snprintf(err, errlen, "%s %s%s%s", what, path, *g ? ": " : "", g);
	return -1;
}

bool
gtiff_path(const char *path)
{
	size_t		n = path ? strlen(path) : 0;

	return (n > 4 && strcasecmp(path + n - 4, ".tif") == 0) ||
		(n > 5 && strcasecmp(path + n - 5, ".tiff") == 0);
}

/* The spatial reference of srs, or NULL with err set */
static OGRSpatialReferenceH
srs_parse(const char *srs, char *err, size_t errlen)
{
	OGRSpatialReferenceH h;

	if (gdal_load(err, errlen) != 0)
		return NULL;
	gd.CPLErrorReset();
	h = gd.OSRNewSpatialReference(NULL);
	if (h != NULL && gd.OSRSetFromUserInput(h, srs) == OGRERR_NONE)
	{
		gd.OSRSetAxisMappingStrategy(h, OAMS_TRADITIONAL_GIS_ORDER);
		return h;
	}
	snprintf(err, errlen, "GDAL does not recognise the CRS '%.200s'%s%.300s", srs,
			 gd.CPLGetLastErrorType() >= CE_Failure ? ": " : "",
			 gd.CPLGetLastErrorType() >= CE_Failure ? gd.CPLGetLastErrorMsg() : "");
	if (h)
		gd.OSRDestroySpatialReference(h);
	return NULL;
}

int
gtiff_check_srs(const char *srs, char *err, size_t errlen)
{
	OGRSpatialReferenceH h = srs_parse(srs, err, errlen);

	if (h == NULL)
		return -1;
	gd.OSRDestroySpatialReference(h);
	return 0;
}

gtiff_out *
gtiff_reserve(const char *path, char *err, size_t errlen)
{
	static bool registered;
	gtiff_out  *g;
	struct stat st;
	char		msg[700];
	int			fd;

	if (gdal_load(msg, sizeof(msg)) != 0)
	{
		snprintf(err, errlen, "cannot write %s: %s", path, msg);
		return NULL;
	}
	if ((g = calloc(1, sizeof(gtiff_out))) == NULL)
	{
		snprintf(err, errlen, "out of memory");
		return NULL;
	}
	if (strlen(path) >= sizeof(g->path) - 32)
	{
		snprintf(err, errlen, "cannot write %.200s...: the path is too long", path);
		free(g);
		return NULL;
	}
	if (stat(path, &st) == 0 && !S_ISREG(st.st_mode))
	{
		snprintf(err, errlen, "cannot write %s: it exists and is not a file", path);
		free(g);
		return NULL;
	}
	snprintf(g->path, sizeof(g->path), "%s", path);
	snprintf(g->tmp, sizeof(g->tmp), "%s.%ld.tmp", path, (long) getpid());
	/* O_EXCL: never write through someone else's file */
	fd = open(g->tmp, O_WRONLY | O_CREAT | O_EXCL, 0666);
	if (fd < 0)
	{
		snprintf(err, errlen, "cannot write %s: cannot create %s: %s", path, g->tmp,
				 strerror(errno));
		free(g);
		return NULL;
	}
	close(fd);
	if (!registered)
		remove_pending_at_exit();
	registered = true;
	snprintf(pending_aux, sizeof(pending_aux), "%s.aux.xml", g->tmp);
	snprintf(pending, sizeof(pending), "%s", g->tmp);
	return g;
}

int
gtiff_threads(int threads)
{
	long		cpus = sysconf(_SC_NPROCESSORS_ONLN);

	if (threads <= 0)
		threads = cpus < 1 ? 1 : (int) (cpus < GTIFF_THREADS ? cpus : GTIFF_THREADS);
	return threads < GTIFF_THREADS ? threads : GTIFF_THREADS;
}

int
gtiff_open(gtiff_out *g, size_t width, size_t height, const double gt[6], const char *srs,
		   double nodata, bool float32, int threads, char *err, size_t errlen)
{
	/*
	 * NUM_THREADS: DEFLATE is most of a large grid's writing, and GDAL's
	 * threads compress blocks while the rows come.  A block's bytes do
	 * not depend on the thread that compresses it, nor the file on their
	 * number (test/cli.sh compares -t 1 with -t 2).
	 */
	char		nt[32];
	const char *co[] = {"TILED=YES", "BLOCKXSIZE=256", "BLOCKYSIZE=256",
		"COMPRESS=DEFLATE", "PREDICTOR=3", "BIGTIFF=IF_SAFER", nt, NULL};
	GDALDriverH drv = gd.GDALGetDriverByName("GTiff");
	double		t[6];

	snprintf(nt, sizeof(nt), "NUM_THREADS=%d", gtiff_threads(threads));

	if (width > 2147483647 || height > 2147483647)
	{
		snprintf(err, errlen, "cannot write %s: a GeoTIFF has at most 2147483647 %s", g->path,
				 width > height ? "columns" : "rows");
		return -1;
	}
	if (float32 && (double) (float) nodata != nodata)
	{
		snprintf(err, errlen, "--type Float32: the nodata %.17g is not a Float32 value", nodata);
		return -1;
	}
	g->width = width;
	g->height = height;
	g->float32 = float32;
	gd.CPLErrorReset();
	g->ds = drv ? gd.GDALCreate(drv, g->tmp, (int) width, (int) height, 1,
							 float32 ? GDT_Float32 : GDT_Float64, (CSLConstList) co) : NULL;
	if (g->ds == NULL)
		return fail(err, errlen, "cannot create the GeoTIFF", g->path);
	g->band = gd.GDALGetRasterBand(g->ds, 1);
	memcpy(t, gt, sizeof(t));
	if (gd.GDALSetGeoTransform(g->ds, t) != CE_None ||
		gd.GDALSetRasterNoDataValue(g->band, nodata) != CE_None)
		return fail(err, errlen, "cannot georeference", g->path);
	if (srs)
	{
		OGRSpatialReferenceH h = srs_parse(srs, err, errlen);
		CPLErr		rc;

		if (h == NULL)
			return -1;
		rc = gd.GDALSetSpatialRef(g->ds, h);
		gd.OSRDestroySpatialReference(h);
		if (rc != CE_None)
			return fail(err, errlen, "cannot set the CRS of", g->path);
	}
	return 0;
}

/* Rows [row0, row0 + n) of the file from values (width doubles a row), tile column by tile column */
static int
put_rows(gtiff_out *g, size_t row0, size_t n, const double *values, char *err, size_t errlen)
{
	gd.CPLErrorReset();
	for (size_t c0 = 0; c0 < g->width; c0 += GTIFF_TILE)
	{
		size_t		cw = g->width - c0 < GTIFF_TILE ? g->width - c0 : GTIFF_TILE;

		if (gd.GDALRasterIOEx(g->band, GF_Write, (int) c0, (int) row0, (int) cw, (int) n,
						   (void *) (values + c0), (int) cw, (int) n, GDT_Float64,
						   sizeof(double), (GSpacing) (g->width * sizeof(double)), NULL) != CE_None ||
			gd.CPLGetLastErrorType() >= CE_Failure)
			return fail(err, errlen, "error writing", g->path);
	}
	return 0;
}

int
gtiff_write_rows(gtiff_out *g, size_t y0, size_t nrows, const double *values, char *err,
				 size_t errlen)
{
	if (g->ds == NULL || y0 != g->next_row || nrows > g->height - y0)
	{
		snprintf(err, errlen, "%s: rows from %zu written when row %zu was due (of %zu)", g->path,
				 y0, g->next_row, g->height);
		return -1;
	}
	if (g->float32)
		for (size_t i = 0; i < nrows * g->width; i++)
			if (fabs(values[i]) > FLT_MAX)
			{
				snprintf(err, errlen, "--type Float32: the value %.17g (row %zu, column %zu) is "
						 "beyond Float32's range; use Float64", values[i],
						 y0 + i / g->width, i % g->width);
				return -1;
			}
	while (nrows > 0)
	{
		size_t		top = g->next_row - g->next_row % GTIFF_TILE,
					end = top + GTIFF_TILE < g->height ? top + GTIFF_TILE : g->height,
					need = end - g->next_row,
					take = nrows < need ? nrows : need;

		if (g->gathered == 0 && take == need)
		{
			/* a whole tile row from the caller's rows (next_row == top) */
			if (put_rows(g, top, take, values, err, errlen) != 0)
				return -1;
		}
		else
		{
			if (g->strip == NULL)
			{
				size_t		rows = g->height < GTIFF_TILE ? g->height : GTIFF_TILE;

				g->strip = malloc(rows * g->width * sizeof(double));
				if (g->strip == NULL)
				{
					snprintf(err, errlen, "out of memory for a strip of %s", g->path);
					return -1;
				}
			}
			memcpy(g->strip + g->gathered * g->width, values, take * g->width * sizeof(double));
			g->gathered += take;
			if (take == need)
			{
				if (put_rows(g, top, g->gathered, g->strip, err, errlen) != 0)
					return -1;
				g->gathered = 0;
			}
		}
		g->next_row += take;
		values += take * g->width;
		nrows -= take;
	}
	return 0;
}

int
gtiff_close(gtiff_out *g, char *err, size_t errlen)
{
	char		aux[4300],
				tmp_aux[4300];
	int			rc = 0;

	if (g->next_row != g->height)
	{
		snprintf(err, errlen, "%s: %zu of %zu rows written", g->path, g->next_row, g->height);
		gtiff_discard(g);
		return -1;
	}
	gd.CPLErrorReset();
	gd.GDALClose(g->ds);
	g->ds = NULL;
	if (gd.CPLGetLastErrorType() >= CE_Failure)
		rc = fail(err, errlen, "error writing", g->path);
	else if (rename(g->tmp, g->path) != 0)
	{
		snprintf(err, errlen, "cannot rename %s to %s: %s", g->tmp, g->path, strerror(errno));
		rc = -1;
	}
	else
	{
		/* the file is in place: its sidecar, GDAL's new one or none */
		pending[0] = '\0';
		snprintf(aux, sizeof(aux), "%s.aux.xml", g->path);
		snprintf(tmp_aux, sizeof(tmp_aux), "%s.aux.xml", g->tmp);
		if (access(tmp_aux, F_OK) == 0 ? rename(tmp_aux, aux) != 0 :
			(unlink(aux) != 0 && errno != ENOENT))
		{
			snprintf(err, errlen, "%s written, but its sidecar %s not replaced: %s", g->path, aux,
					 strerror(errno));
			unlink(tmp_aux);
			rc = -1;
		}
	}
	gtiff_discard(g);
	return rc;
}

void
gtiff_discard(gtiff_out *g)
{
	if (g == NULL)
		return;
	if (g->ds)
		gd.GDALClose(g->ds);
	remove_pending();
	free(g->strip);
	free(g);
}
