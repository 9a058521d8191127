/*
 * tiled.c
 *		./tdc --max-memory MB [--tmpdir DIR]: the triangulation of an input
 *		that does not fit, tile by tile through files.
 *
 * When the one-shot run (the input, the engine, the result) would not fit
 * in MB, the input is cut into tiles on disk and triangulated tile by tile
 * with the core's exact tiling (src/core/tile.c), and the triangles are
 * written as each tile finishes.  Two sequential reads of the input (text
 * input is first converted to a temporary .bin):
 *	1	bounding box, convex hull (in chunks: the hull of a union is the
 *		hull of the parts' hulls, and a point inside a rectangle inside the
 *		hull so far is skipped) and counts on a fine grid, whose box comes
 *		from a sample of the file (counted again in a pass of its own when
 *		the sample was far off); the grid is cut into tiles of at most
 *		tile_max points by median splits along the longer side (kd-tree of
 *		cells), so that clustered data gets small tiles where it is dense;
 *	2	each point appended to its tile's file, and to the halo file of
 *		every other tile whose first known region holds it; the two halves
 *		of the input on two threads, each with its own files, read back one
 *		after the other.
 * A point's cell is decided exactly against the doubles of the cell sides,
 * so a tile's points lie in its cells' box, and its first known region is
 * fixed before binning: K = that box plus a halo of 8 mean point spacings,
 * and as extra known boxes the bands along the hull edges near it.  The
 * first run of a tile reads its two files, and nothing else; it
 * triangulates; tdc_tile_finish either hands over the tile's triangles or
 * asks for a larger K, and the tile runs again (first with the bands of the
 * hull edges the request meets, then with a larger K), gathering every
 * point inside the new region from the tile files whose boxes meet it.
 *
 * Memory: the largest tile with its halo is bounded by tile_max times a
 * growth allowance; a tile whose K would exceed the budget is an error,
 * never a silent overrun (a first region too big for the budget is
 * gathered and shrunk as a re-run's is).  Duplicates share their cell,
 * hence their tile, and the tile and halo files keep input order, so the Z
 * of a vertex is that of its first input point, as in the one-shot run.
 * The write buffers of the files take a sixteenth of the budget.
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "cli.h"

#define FINE_GRID	512			/* cells per side of the counting grid */
#define CHUNK		(1 << 16)	/* points per read in the scans */
#define MAX_TILES	900			/* open files while binning */

typedef struct tile_info
{
	int			c0,
				c1,
				r0,
				r1;				/* cells [c0, c1) x [r0, r1) */
	size_t		count;
	double		bb[4];			/* exact box of its points */
} tile_info;

char		tmp_dir[4096];

void
tmp_cleanup(void)
{
	DIR		   *d;
	struct dirent *e;

	if (tmp_dir[0] == '\0')
		return;
	if ((d = opendir(tmp_dir)) != NULL)
	{
		while ((e = readdir(d)) != NULL)
		{
			char		p[4400];

			if (e->d_name[0] == '.')
				continue;
			snprintf(p, sizeof(p), "%s/%s", tmp_dir, e->d_name);
			unlink(p);
		}
		closedir(d);
	}
	rmdir(tmp_dir);
	tmp_dir[0] = '\0';
}

static FILE *
tmp_open(const char *name, const char *mode)
{
	char		p[4400];
	FILE	   *f;

	snprintf(p, sizeof(p), "%s/%s", tmp_dir, name);
	f = fopen(p, mode);
	if (f == NULL)
		die(1, "cannot open temporary file %s", p);
	return f;
}

/* Text input to tmp_dir/input.xy (+ input.z): returns n, sets *has_z. */
size_t
text_to_bin(const char *path, int *has_z)
{
	FILE	   *f = strcmp(path, "-") == 0 ? stdin : fopen(path, "r"),
			   *fxy,
			   *fz = NULL;
	char	   *line = NULL;
	size_t		cap = 0,
				lineno = 0,
				n = 0;
	int			dims = 0;

	if (f == NULL)
		die(1, "cannot open %s", path);
	fxy = tmp_open("input.xy", "wb");
	while (getline(&line, &cap, f) >= 0)
	{
		double		v[3];

		if (parse_line(line, ++lineno, v, &dims) == 0)
			continue;
		if (dims == 3 && fz == NULL)
		{
			if (n > 0)
				die(1, "line %s: every line must hold 'x y' or every line 'x y z'", "1");
			fz = tmp_open("input.z", "wb");
		}
		if (fwrite(v, 8, 2, fxy) != 2 || (fz && fwrite(v + 2, 8, 1, fz) != 1))
			die(1, "cannot write temporary files in %s", tmp_dir);
		n++;
	}
	free(line);
	if (f != stdin)
		fclose(f);
	if (fclose(fxy) != 0 || (fz && fclose(fz) != 0))
		die(1, "cannot write temporary files in %s", tmp_dir);
	*has_z = fz != NULL;
	return n;
}

/* Reads the .bin source (and z) in chunks: the caller's loop. */
typedef struct source
{
	FILE	   *fxy,
			   *fz;
	double	   *xy,
			   *z;
	size_t		left;			/* points still to read */
} source;

static void
source_open(source *s, const char *xypath, const char *zpath)
{
	s->fxy = fopen(xypath, "rb");
	s->fz = zpath ? fopen(zpath, "rb") : NULL;
	if (s->fxy == NULL || (zpath && s->fz == NULL))
		die(1, "cannot open %s", xypath);
	s->xy = malloc(16 * (size_t) CHUNK);
	s->z = zpath ? malloc(8 * (size_t) CHUNK) : NULL;
	if (s->xy == NULL || (zpath && s->z == NULL))
		die(1, "out of memory%s", "");
	s->left = SIZE_MAX;
}

/* Read only the points [from, from + count) from now on. */
static void
source_range(source *s, size_t from, size_t count)
{
	if (fseeko(s->fxy, (off_t) from * 16, SEEK_SET) != 0 ||
		(s->fz && fseeko(s->fz, (off_t) from * 8, SEEK_SET) != 0))
		die(1, "cannot seek in the input%s", "");
	s->left = count;
}

static size_t
source_read(source *s)
{
	size_t		k = fread(s->xy, 16, s->left < CHUNK ? s->left : CHUNK, s->fxy);

	s->left -= k;
	if (s->fz && fread(s->z, 8, k, s->fz) != k)
		die(1, "short read on the temporary z file%s", "");
	return k;
}

static void
source_close(source *s)
{
	fclose(s->fxy);
	if (s->fz)
		fclose(s->fz);
	free(s->xy);
	free(s->z);
}

static int
fine_cell(double v, double lo, double scale)
{
	int			c = (int) ((v - lo) * scale);

	return c < 0 ? 0 : c >= FINE_GRID ? FINE_GRID - 1 : c;
}

/* Points in cells [c0, c1) x [r0, r1) from the prefix sums. */
static size_t
cells_count(const size_t *ps, int c0, int c1, int r0, int r1)
{
	const int	w = FINE_GRID + 1;

	return ps[r1 * w + c1] - ps[r0 * w + c1] - ps[r1 * w + c0] + ps[r0 * w + c0];
}

/* kd-split of the cell rectangle until every tile holds at most tile_max points. */
static void
plan_tiles(const size_t *ps, int c0, int c1, int r0, int r1, double cw, double ch,
		   size_t tile_max, tile_info *tiles, int *nt)
{
	size_t		cnt = cells_count(ps, c0, c1, r0, r1),
				k;
	bool		by_x;
	int			lo,
				hi;

	if (cnt == 0)
		return;
	if (cnt <= tile_max || (c1 - c0 == 1 && r1 - r0 == 1))
	{
		if (cnt > tile_max)
			die(1, "the points are too clustered for --max-memory: one cell of the tiling grid holds %s points", "more than a tile's share of");
		if (*nt >= MAX_TILES)
			die(1, "--max-memory is too small for this input: more than %s tiles would be needed", "900");
		tiles[*nt].c0 = c0;
		tiles[*nt].c1 = c1;
		tiles[*nt].r0 = r0;
		tiles[*nt].r1 = r1;
		tiles[*nt].count = cnt;
		(*nt)++;
		return;
	}
	by_x = (c1 - c0 > 1) && ((c1 - c0) * cw >= (r1 - r0) * ch || r1 - r0 == 1);

	/*
	 * The rectangle needs k = ceil(cnt / tile_max) tiles: cut it at the
	 * fraction floor(k / 2) / k, so that each side needs a whole number of
	 * tiles.  Halving instead would round the count up to a power of two:
	 * 16 tiles where 9 do, each smaller, with more halo in all.  The cut is
	 * the smallest cell line with at least that fraction below.
	 */
	k = (cnt + tile_max - 1) / tile_max;
	lo = by_x ? c0 + 1 : r0 + 1;
	hi = by_x ? c1 - 1 : r1 - 1;
	while (lo < hi)
	{
		int			mid = (lo + hi) / 2;
		size_t		below = by_x ? cells_count(ps, c0, mid, r0, r1) : cells_count(ps, c0, c1, r0, mid);

		if (below * k >= cnt * (k / 2))
			hi = mid;
		else
			lo = mid + 1;
	}
	if (by_x)
	{
		plan_tiles(ps, c0, lo, r0, r1, cw, ch, tile_max, tiles, nt);
		plan_tiles(ps, lo, c1, r0, r1, cw, ch, tile_max, tiles, nt);
	}
	else
	{
		plan_tiles(ps, c0, c1, r0, lo, cw, ch, tile_max, tiles, nt);
		plan_tiles(ps, c0, c1, lo, r1, cw, ch, tile_max, tiles, nt);
	}
}

static bool
box_meets(const double *a, const double *b)
{
	return a[0] <= b[2] && b[0] <= a[2] && a[1] <= b[3] && b[1] <= a[3];
}

static void
box_add(double *b, double x, double y)
{
	b[0] = fmin(b[0], x);
	b[1] = fmin(b[1], y);
	b[2] = fmax(b[2], x);
	b[3] = fmax(b[3], y);
}

static void
box_union2(double *b, const double *a)
{
	b[0] = fmin(b[0], a[0]);
	b[1] = fmin(b[1], a[1]);
	b[2] = fmax(b[2], a[2]);
	b[3] = fmax(b[3], a[3]);
}

/*
 * Bytes one tile run of m points (with z or not) may hold at once: the
 * gathered points and labels, the engine, tile.c's per-site arrays (the 4
 * bytes once taken by the input map now hold its block grid for the deep
 * sites, under a byte per point), and the triangle indices (at most 2m
 * triangles of 3 size_t).
 */
static size_t
tile_bytes(size_t m, const tdc_options *opt, int has_z)
{
	return tdc_estimate_memory(m, opt) + m * (16 + 8 + (has_z ? 8 : 0) + 4 + 8 + 1 + 48) + (1 << 20);
}


static double
now_s(void)
{
	struct timespec t;

	clock_gettime(CLOCK_MONOTONIC, &t);
	return t.tv_sec + t.tv_nsec * 1e-9;
}

static void
write_tri(FILE *f, const double *q, const double *qz, const size_t *v)
{
	for (int k = 0; k < 3; k++)
	{
		const double *p = q + 2 * v[k];

		if (qz)
			fprintf(f, k ? " %.17g %.17g %.17g" : "%.17g %.17g %.17g", p[0], p[1], qz[v[k]]);
		else
			fprintf(f, k ? " %.17g %.17g" : "%.17g %.17g", p[0], p[1]);
	}
	fputc('\n', f);
}

/*
 * The fine grid's cell of v along one axis: the c with cut[c] <= v <
 * cut[c + 1] (the last cell closed), cut[] the doubles of the cell sides,
 * non-decreasing.  Exact: a tile's cell box holds every point binned to
 * it, so its K and its halo are known before the points are binned.
 */
static int
cell_of(double v, double lo, double scale, const double *cut)
{
	int			c = fine_cell(v, lo, scale);

	while (c > 0 && v < cut[c])
		c--;
	while (c < FINE_GRID - 1 && v >= cut[c + 1])
		c++;
	return c;
}

/*
 * The first K of tile ti (its cell box plus a halo of 8 mean spacings), h,
 * and in mark[] (nhull bytes, cleared by the caller) the hull bands it
 * takes as extra boxes.
 */
static void
first_known(const tile_info *ti, const double *xcut, const double *ycut,
			const double *bands, size_t nhull, double K[4], double *h, uint8_t *mark)
{
	double		near[4],
				g;

	K[0] = xcut[ti->c0];
	K[1] = ycut[ti->r0];
	K[2] = xcut[ti->c1];
	K[3] = ycut[ti->r1];
	*h = 8 * sqrt((K[2] - K[0]) * (K[3] - K[1]) / (double) ti->count);
	K[0] -= *h;
	K[1] -= *h;
	K[2] += *h;
	K[3] += *h;

	/*
	 * Extra known boxes: the boxes of the hull edges near K, grown by a
	 * band of 16 mean spacings.  A long hull edge has one triangle whose
	 * circle bulges far out of C: only its thin part inside C, along the
	 * edge, must be known, and the band holds it, without widening K along
	 * the whole edge.  The bands also bring in the hull's vertices, so
	 * every own hull edge is certified at once.
	 *
	 * The bands of the hull edges near K, not only those meeting it:
	 * slivers under a long hull edge have their circles' parts inside C
	 * along the neighbouring edges too (border tiles of 100M uniform points
	 * re-ran in 7 cases of 12 without this).  Within K's size of K, the
	 * bands along a side hold about 96 / sqrt(count) of the tile's points
	 * (a band is 32 spacings wide), against a whole tile for a re-run:
	 * taken when that is under 5 %, else only the bands meeting K, and a
	 * re-run adds what is missing.
	 */
	g = ti->count >= 4000000 ? fmax(K[2] - K[0], K[3] - K[1]) : 0;
	near[0] = K[0] - g;
	near[1] = K[1] - g;
	near[2] = K[2] + g;
	near[3] = K[3] + g;
	for (size_t i = 0; nhull > 1 && i < nhull; i++)
		mark[i] = box_meets(bands + 4 * i, near);
}

/* Buffered appends of fixed-size records to one temporary file. */
typedef struct recfile
{
	FILE	   *f;
	double	   *buf;
	size_t		len,			/* doubles in buf */
				cap;
	size_t		count;			/* records written */
} recfile;

static void
rec_flush(recfile *r)
{
	if (r->len > 0 && fwrite(r->buf, 8, r->len, r->f) != r->len)
		die(1, "cannot write temporary files in %s", tmp_dir);
	r->len = 0;
}

static inline void
rec_put(recfile *r, const double *v, int w)
{
	if (r->len + w > r->cap)
		rec_flush(r);
	for (int k = 0; k < w; k++)
		r->buf[r->len + k] = v[k];
	r->len += w;
	r->count++;
}

/*
 * Tile t's file of a kind ("tile": its own points, "halo": the others of
 * its first region) written by binning part `part`: the parts hold
 * consecutive ranges of the input, so read one after the other they keep
 * input order.
 */
static FILE *
part_open(const char *kind, int t, int part, const char *mode)
{
	char		name[48];

	snprintf(name, sizeof(name), "%s%d.%d", kind, t, part);
	return tmp_open(name, mode);
}

/* Reads a tile's file of a kind across its parts, in order. */
typedef struct mreader
{
	const char *kind;
	int			t,
				part,
				nparts;
	FILE	   *f;
} mreader;

static void
mr_open(mreader *m, const char *kind, int t, int nparts)
{
	m->kind = kind;
	m->t = t;
	m->part = 0;
	m->nparts = nparts;
	m->f = part_open(kind, t, 0, "rb");
}

/* Up to count whole records of size bytes; 0 at the end of the last part. */
static size_t
mr_read(mreader *m, void *buf, size_t size, size_t count)
{
	size_t		got;

	while ((got = fread(buf, size, count, m->f)) == 0 && m->part + 1 < m->nparts)
	{
		fclose(m->f);
		m->f = part_open(m->kind, m->t, ++m->part, "rb");
	}
	return got;
}

static void
mr_close(mreader *m)
{
	fclose(m->f);
}

static void
rec_open(recfile *r, const char *kind, int t, int part, size_t cap)
{
	r->f = part_open(kind, t, part, "wb");
	r->buf = malloc(8 * cap);
	r->cap = cap;
	r->len = 0;
	r->count = 0;
	if (r->buf == NULL)
		die(1, "out of memory%s", "");
}

static void
rec_close(recfile *r)
{
	if (r->f == NULL)
		return;
	rec_flush(r);
	if (fclose(r->f) != 0)
		die(1, "cannot write temporary files in %s (disk full?)", tmp_dir);
	free(r->buf);
	r->f = NULL;
	r->buf = NULL;
}

/* Read exactly k records of w doubles of tile t's file of a kind into buf. */
static void
read_all(const char *kind, int t, int nparts, double *buf, size_t k, int w)
{
	mreader		m;
	size_t		at = 0,
				got;

	mr_open(&m, kind, t, nparts);
	while (at < k && (got = mr_read(&m, buf + w * at, 8 * (size_t) w, k - at)) > 0)
		at += got;
	mr_close(&m);
	if (at != k)
		die(1, "short read on a temporary file in %s", tmp_dir);
}

/*
 * TDC_TILE_CHECK=1 (tests): the points inside K or an extra box, counted
 * from every tile file, for checking a first run's tile and halo files.
 */
static size_t
count_known(const tile_info *tiles, int nt, int nparts, const double *K, const double *extra,
			size_t nextra, int w)
{
	size_t		m = 0,
				got;
	double		rec[4 * 1024];

	for (int s = 0; s < nt; s++)
	{
		mreader		f;

		if (tiles[s].count == 0)
			continue;
		mr_open(&f, "tile", s, nparts);
		while ((got = mr_read(&f, rec, 8 * (size_t) w, 1024)) > 0)
			for (size_t i = 0; i < got; i++)
			{
				const double *p = rec + w * i;
				bool		in = p[0] >= K[0] && p[0] <= K[2] && p[1] >= K[1] && p[1] <= K[3];

				for (size_t e = 0; e < nextra && !in; e++)
				{
					const double *x = extra + 4 * e;

					in = p[0] >= x[0] && p[0] <= x[2] && p[1] >= x[1] && p[1] <= x[3];
				}
				m += in;
			}
		mr_close(&f);
	}
	return m;
}

/*
 * Step 1 over the input points [from, from + count): their box, convex
 * hull and, when the grid is known (grid not NULL), the counts of its
 * cells.  The hull of a union is the hull of the parts' hulls; a point
 * strictly inside a rectangle inside the hull so far (inner) cannot be a
 * vertex of it, and for most data that rectangle holds almost every point:
 * only the others go to the chunk's hull.  Runs as two parts on two
 * threads when the grid is known.
 */
typedef struct scan_work
{
	const char *xypath;
	size_t		from,
				count;
	const double *grid,
			   *xcut,
			   *ycut;
	double		sx,
				sy;
	uint32_t   *counts;
	/* results */
	double		bb[4];
	double	   *hull;
	size_t		nhull;
	bool		bad;			/* a coordinate not finite or out of range */
} scan_work;

static void *
scan_range(void *arg)
{
	scan_work  *sw = arg;
	source		src;
	size_t		k,
				nhull = 0;
	double	   *hull = NULL,
				inner[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
			   *bb = sw->bb;
	const double *grid = sw->grid,
			   *xcut = sw->xcut,
			   *ycut = sw->ycut;
	double		sx = sw->sx,
				sy = sw->sy;
	uint32_t   *counts = sw->counts;
	bool		counted = grid != NULL;

	bb[0] = bb[1] = INFINITY;
	bb[2] = bb[3] = -INFINITY;
	sw->bad = false;
	source_open(&src, sw->xypath, NULL);
	source_range(&src, sw->from, sw->count);
	while ((k = source_read(&src)) > 0)
	{
		double	   *buf,
				   *h2;
		size_t		n2,
					m = 0;

		buf = malloc(16 * (k + nhull));
		if (buf == NULL)
			die(1, "out of memory%s", "");
		for (size_t i = 0; i < k; i++)
		{
			double		x = src.xy[2 * i],
						y = src.xy[2 * i + 1];

			if (!isfinite(x) || !isfinite(y) ||
				(x != 0 && (fabs(x) < TDC_COORD_MIN || fabs(x) > TDC_COORD_MAX)) ||
				(y != 0 && (fabs(y) < TDC_COORD_MIN || fabs(y) > TDC_COORD_MAX)))
			{
				sw->bad = true;
				continue;
			}
			if (x < bb[0])
				bb[0] = x;
			if (x > bb[2])
				bb[2] = x;
			if (y < bb[1])
				bb[1] = y;
			if (y > bb[3])
				bb[3] = y;
			if (counted)
				counts[cell_of(y, grid[1], sy, ycut) * FINE_GRID + cell_of(x, grid[0], sx, xcut)]++;
			if (x > inner[0] && x < inner[2] && y > inner[1] && y < inner[3])
				continue;
			buf[2 * m] = x;
			buf[2 * m + 1] = y;
			m++;
		}
		if (nhull)
			memcpy(buf + 2 * m, hull, 16 * nhull);
		if (tdc_convex_hull(buf, m + nhull, &h2, &n2) != TDC_OK)
			die(1, "out of memory%s", "");
		free(buf);
		free(hull);
		hull = h2;
		nhull = n2;
		/* the hull's box shrunk towards its centre until its corners are strictly inside */
		if (nhull >= 3)
		{
			double		hb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
						cx,
						cy;

			for (size_t i = 0; i < nhull; i++)
				box_add(hb, hull[2 * i], hull[2 * i + 1]);
			cx = 0.5 * (hb[0] + hb[2]);
			cy = 0.5 * (hb[1] + hb[3]);
			for (double f = 0.98; f > 0.2; f -= 0.16)
			{
				double		r[4] = {cx - f * (cx - hb[0]), cy - f * (cy - hb[1]),
				cx + f * (hb[2] - cx), cy + f * (hb[3] - cy)};
				bool		in = r[0] < r[2] && r[1] < r[3];
				double	   *hb2 = malloc(16 * (nhull + 4)),
						   *h3 = NULL;
				size_t		n3 = 0;

				/*
				 * The closed rectangle is inside the closed hull when adding
				 * its corners leaves the hull as it is; its open inside is
				 * then inside the hull's, whose points are no vertices.
				 */
				if (hb2 == NULL)
					die(1, "out of memory%s", "");
				memcpy(hb2, hull, 16 * nhull);
				memcpy(hb2 + 2 * nhull, (double[8]) {r[0], r[1], r[2], r[1], r[2], r[3], r[0], r[3]}, 64);
				if (in && tdc_convex_hull(hb2, nhull + 4, &h3, &n3) != TDC_OK)
					die(1, "out of memory%s", "");
				in = in && n3 == nhull && memcmp(h3, hull, 16 * nhull) == 0;
				free(hb2);
				free(h3);
				if (in)
				{
					memcpy(inner, r, sizeof(r));
					break;
				}
			}
		}
	}
	source_close(&src);
	sw->hull = hull;
	sw->nhull = nhull;
	return NULL;
}

/*
 * Step 2 over the input points [from, from + count): each point to its
 * tile's file, and to the halo file of every other tile whose first known
 * region holds it; the exact box of each tile's points in bb.  Binning
 * runs as two such parts on two threads when the files allow.
 */
typedef struct bin_work
{
	/* shared, read only */
	const char *xypath,
			   *zpath;
	const double *grid,
			   *xcut,
			   *ycut,
			   *kfirst,
			   *bands;
	double		sx,
				sy;
	const int16_t *cell_tile,
			   *cell_halo;
	const uint32_t *cell_off;
	const size_t *band_off,
			   *band_idx;
	bool		use_halo;
	int			w,
				nt;
	/* this part's */
	size_t		from,
				count;
	recfile    *own,
			   *halo;
	double	   *bb;				/* nt boxes */
} bin_work;

static void *
bin_range(void *arg)
{
	bin_work   *b = arg;
	source		src;
	size_t		k;
	int			w = b->w;

	source_open(&src, b->xypath, b->zpath);
	source_range(&src, b->from, b->count);
	while ((k = source_read(&src)) > 0)
		for (size_t i = 0; i < k; i++)
		{
			double		rec[4] = {src.xy[2 * i], src.xy[2 * i + 1], src.z ? src.z[i] : 0, 0};
			int			cell = cell_of(rec[1], b->grid[1], b->sy, b->ycut) * FINE_GRID +
				cell_of(rec[0], b->grid[0], b->sx, b->xcut),
						t = b->cell_tile[cell];
			double	   *bb = b->bb + 4 * t;

			if (rec[0] < bb[0])
				bb[0] = rec[0];
			if (rec[0] > bb[2])
				bb[2] = rec[0];
			if (rec[1] < bb[1])
				bb[1] = rec[1];
			if (rec[1] > bb[3])
				bb[3] = rec[1];
			rec_put(&b->own[t], rec, w);
			if (!b->use_halo)
				continue;
			for (uint32_t j = b->cell_off[cell]; j < b->cell_off[cell + 1]; j++)
			{
				int			u = b->cell_halo[j];
				const double *K = b->kfirst + 4 * u;
				bool		in = rec[0] >= K[0] && rec[0] <= K[2] && rec[1] >= K[1] && rec[1] <= K[3];

				for (size_t e = b->band_off[u]; e < b->band_off[u + 1] && !in; e++)
				{
					const double *x = b->bands + 4 * b->band_idx[e];

					in = rec[0] >= x[0] && rec[0] <= x[2] && rec[1] >= x[1] && rec[1] <= x[3];
				}
				if (in)
				{
					rec[w] = t;
					rec_put(&b->halo[u], rec, w + 1);
				}
			}
		}
	source_close(&src);
	for (int t = 0; t < b->nt; t++)
	{
		rec_close(&b->own[t]);
		if (b->use_halo)
			rec_close(&b->halo[t]);
	}
	return NULL;
}

/*
 * The counting grid's box from a sample of the .bin source (256 runs of 256
 * points spread over the file), grown by two cells a side, so that pass 1
 * can count as it finds the box and hull.  The cells stay exact whatever
 * the sample (cell_of clamps, and the outer cells are then widened to the
 * true box); a box far off the true one only makes a poor plan, and pass 1
 * then counts again.  False when n is small or the sample is flat.
 */
static bool
sample_grid(const char *xypath, size_t n, double g[4])
{
	FILE	   *f;
	double		buf[2 * 256];

	if (n < ((size_t) 1 << 18) || (f = fopen(xypath, "rb")) == NULL)
		return false;
	g[0] = g[1] = INFINITY;
	g[2] = g[3] = -INFINITY;
	for (size_t j = 0; j < 256; j++)
	{
		size_t		got;

		if (fseeko(f, (off_t) ((n - 256) / 255 * j) * 16, SEEK_SET) != 0)
			break;
		got = fread(buf, 16, 256, f);
		for (size_t i = 0; i < got; i++)
			if (isfinite(buf[2 * i]) && isfinite(buf[2 * i + 1]))
				box_add(g, buf[2 * i], buf[2 * i + 1]);
	}
	fclose(f);
	if (!(g[2] > g[0]) || !(g[3] > g[1]) || !isfinite(g[2] - g[0]) || !isfinite(g[3] - g[1]))
		return false;
	{
		double		mx = (g[2] - g[0]) * 2 / FINE_GRID,
					my = (g[3] - g[1]) * 2 / FINE_GRID;

		g[0] -= mx;
		g[1] -= my;
		g[2] += mx;
		g[3] += my;
	}
	return isfinite(g[0]) && isfinite(g[1]) && isfinite(g[2]) && isfinite(g[3]);
}

/* The fine grid over box g: scales, cell sizes and the cell sides. */
static void
set_grid(const double *g, double *sx, double *sy, double *cw, double *ch,
		 double *xcut, double *ycut)
{
	*sx = g[2] > g[0] ? FINE_GRID / (g[2] - g[0]) : 0;
	*sy = g[3] > g[1] ? FINE_GRID / (g[3] - g[1]) : 0;
	*cw = (g[2] - g[0]) / FINE_GRID;
	*ch = (g[3] - g[1]) / FINE_GRID;
	for (int c = 0; c <= FINE_GRID; c++)
	{
		xcut[c] = g[0] + c * *cw;
		ycut[c] = g[1] + c * *ch;
	}
	xcut[FINE_GRID] = fmax(xcut[FINE_GRID], g[2]);
	ycut[FINE_GRID] = fmax(ycut[FINE_GRID], g[3]);
}

/*
 * The tiled run.  xypath/zpath: the .bin source (z beside it for text input
 * with z).  budget: bytes.  Returns nothing; dies on errors.
 */
void
run_tiled(const char *xypath, const char *zpath, size_t n, const tdc_options *opt,
		  size_t budget, FILE *out, tiled_stats *st)
{
	source		src;
	size_t		k,
				nhull = 0,
				tile_max,
				*ps;
	double		bb[4] = {INFINITY, INFINITY, -INFINITY, -INFINITY},
			   *hull = NULL,
				sx = 0,
				sy = 0,
				cw,
				ch,
				xcut[FINE_GRID + 1],
				ycut[FINE_GRID + 1],
				grid[4];		/* the fine grid's box */
	bool		counted;		/* pass 1 counted the cells too */
	uint32_t   *counts,
			   *cell_off = NULL;
	int16_t    *cell_tile,
			   *cell_halo = NULL;
	tile_info  *tiles;
	int			nt = 0,
				has_z = zpath != NULL,
				w = has_z ? 3 : 2;
	double	   *extra,
			   *bands,			/* every hull edge's band */
				band,
			   *kfirst = NULL;	/* each tile's first K */
	uint8_t    *inband;			/* is it among this tile's extra boxes */
	size_t	   *band_off = NULL,	/* each tile's first bands: band_idx[band_off[t] ..] */
			   *band_idx = NULL;
	const double **xs;
	size_t	   *halo_count = NULL;	/* each tile's halo file's points */
	int			nparts;			/* binning parts: files per tile and kind */
	bool		use_halo;
	char		err[512];
	double		t0;

	memset(st, 0, sizeof(*st));
	st->n = n;
#ifdef __GLIBC__

	/*
	 * Every tile allocates and frees the same large arrays.  Served by mmap
	 * they go back to the kernel at each free and come back as fresh pages
	 * to fault in and zero, a tenth of the run; kept in the heap they are
	 * reused.  The peak stays that of the largest tile.
	 */
	mallopt(M_MMAP_MAX, 0);
	mallopt(M_TRIM_THRESHOLD, INT32_MAX);
#endif

	/*
	 * 1: box, hull and, on a grid from a sample of the file, the cells'
	 * counts (scan_range).
	 */
	t0 = now_s();
	counts = calloc((size_t) FINE_GRID * FINE_GRID, sizeof(uint32_t));
	if (counts == NULL)
		die(1, "out of memory%s", "");
	counted = sample_grid(xypath, n, grid);
	if (counted)
		set_grid(grid, &sx, &sy, &cw, &ch, xcut, ycut);
	{
		/* the two halves of the input on two threads when the grid is known */
		int			np = counted ? 2 : 1;
		scan_work	sw[2];
		pthread_t	th;
		bool		started = false;

		for (int p = 0; p < np; p++)
		{
			sw[p].xypath = xypath;
			sw[p].from = n / np * p;
			sw[p].count = p == np - 1 ? n - sw[p].from : n / np;
			sw[p].grid = counted ? grid : NULL;
			sw[p].sx = sx;
			sw[p].sy = sy;
			sw[p].xcut = xcut;
			sw[p].ycut = ycut;
			sw[p].counts = p == 0 ? counts : calloc((size_t) FINE_GRID * FINE_GRID, sizeof(uint32_t));
			if (sw[p].counts == NULL)
				die(1, "out of memory%s", "");
		}
		if (np == 2)
			started = pthread_create(&th, NULL, scan_range, &sw[1]) == 0;
		scan_range(&sw[0]);
		if (started)
			pthread_join(th, NULL);
		else if (np == 2)
			scan_range(&sw[1]);
		for (int p = 0; p < np; p++)
			if (sw[p].bad)
				die(1, "a point has a non-finite coordinate or one outside the supported magnitude range%s", "");
		memcpy(bb, sw[0].bb, sizeof(bb));
		hull = sw[0].hull;
		nhull = sw[0].nhull;
		if (np == 2)
		{
			double	   *buf = malloc(16 * (nhull + sw[1].nhull + 1));

			if (buf == NULL)
				die(1, "out of memory%s", "");
			box_union2(bb, sw[1].bb);
			memcpy(buf, hull, 16 * nhull);
			memcpy(buf + 2 * nhull, sw[1].hull, 16 * sw[1].nhull);
			free(hull);
			if (tdc_convex_hull(buf, nhull + sw[1].nhull, &hull, &nhull) != TDC_OK)
				die(1, "out of memory%s", "");
			free(buf);
			free(sw[1].hull);
			for (size_t c = 0; c < (size_t) FINE_GRID * FINE_GRID; c++)
				counts[c] += sw[1].counts[c];
			free(sw[1].counts);
		}
	}

	/*
	 * 2: fine counts (unless pass 1 made them on a grid near the box) and
	 * the tiles.  The outer cells reach the true box: a point's cell still
	 * holds it.
	 */
	if (counted && (bb[0] < grid[0] - cw || bb[2] > grid[2] + cw ||
					bb[1] < grid[1] - ch || bb[3] > grid[3] + ch))
	{
		counted = false;
		memset(counts, 0, sizeof(uint32_t) * FINE_GRID * FINE_GRID);
	}
	if (!counted)
	{
		memcpy(grid, bb, sizeof(grid));
		set_grid(grid, &sx, &sy, &cw, &ch, xcut, ycut);
	}
	xcut[0] = fmin(xcut[0], bb[0]);
	ycut[0] = fmin(ycut[0], bb[1]);
	xcut[FINE_GRID] = fmax(xcut[FINE_GRID], bb[2]);
	ycut[FINE_GRID] = fmax(ycut[FINE_GRID], bb[3]);
	ps = calloc((size_t) (FINE_GRID + 1) * (FINE_GRID + 1), sizeof(size_t));
	tiles = calloc(MAX_TILES, sizeof(tile_info));
	cell_tile = malloc((size_t) FINE_GRID * FINE_GRID * sizeof(int16_t));
	if (!ps || !tiles || !cell_tile)
		die(1, "out of memory%s", "");
	if (!counted)
	{
		source_open(&src, xypath, NULL);
		while ((k = source_read(&src)) > 0)
			for (size_t i = 0; i < k; i++)
				counts[cell_of(src.xy[2 * i + 1], grid[1], sy, ycut) * FINE_GRID +
					   cell_of(src.xy[2 * i], grid[0], sx, xcut)]++;
		source_close(&src);
	}
	for (int r = 0; r < FINE_GRID; r++)
		for (int c = 0; c < FINE_GRID; c++)
			ps[(r + 1) * (FINE_GRID + 1) + c + 1] = counts[r * FINE_GRID + c] +
				ps[r * (FINE_GRID + 1) + c + 1] + ps[(r + 1) * (FINE_GRID + 1) + c] -
				ps[r * (FINE_GRID + 1) + c];
	free(counts);

	/*
	 * The largest tile: its points with the halo and a growth allowance of
	 * 1.5 must fit in the budget.  (It was 2.2 while a sliver along a long
	 * hull edge made corner tiles grow; tile.c now bounds such a triangle's
	 * circle by its segment over the hull edge.  A tile that still outgrows
	 * the budget is first shrunk back, see below.)
	 */
	for (tile_max = n; tile_max > 1000 && tile_bytes(tile_max * 3 / 2, opt, has_z) > budget;)
		tile_max = tile_max * 9 / 10;
	plan_tiles(ps, 0, FINE_GRID, 0, FINE_GRID, cw, ch, tile_max, tiles, &nt);
	free(ps);
	for (int t = 0; t < nt; t++)
	{
		tiles[t].bb[0] = tiles[t].bb[1] = INFINITY;
		tiles[t].bb[2] = tiles[t].bb[3] = -INFINITY;
		for (int r = tiles[t].r0; r < tiles[t].r1; r++)
			for (int c = tiles[t].c0; c < tiles[t].c1; c++)
				cell_tile[r * FINE_GRID + c] = (int16_t) t;
	}
	st->tiles = nt;

	/* the hull bands */
	extra = malloc(32 * (nhull + 1));
	bands = malloc(32 * (nhull + 1));
	inband = calloc(nhull + 1, 1);
	xs = malloc(sizeof(double *) * (nhull + 1));
	band = 16 * sqrt((bb[2] - bb[0]) * (bb[3] - bb[1]) / (double) (n ? n : 1));
	if (extra == NULL || bands == NULL || inband == NULL || xs == NULL)
		die(1, "out of memory%s", "");
	for (size_t i = 0; nhull > 1 && i < nhull; i++)
	{
		const double *a = hull + 2 * i,
				   *b = hull + 2 * ((i + 1) % nhull);

		/*
		 * Longer than the edge by three bands at each end: a sliver whose
		 * circle passes through the edge's end has the part of its disk
		 * inside C reach past that vertex by the disk's error bound, which
		 * for such a circle (radius 1e8) is a few spacings; with one band
		 * the top left tile of 10M uniform points ran twice for 0.7 of a
		 * spacing.
		 */
		bool		along_x = fabs(b[0] - a[0]) >= fabs(b[1] - a[1]);

		bands[4 * i] = fmin(a[0], b[0]) - (along_x ? 3 : 1) * band;
		bands[4 * i + 1] = fmin(a[1], b[1]) - (along_x ? 1 : 3) * band;
		bands[4 * i + 2] = fmax(a[0], b[0]) + (along_x ? 3 : 1) * band;
		bands[4 * i + 3] = fmax(a[1], b[1]) + (along_x ? 1 : 3) * band;
	}

	/*
	 * Each tile's first known region (K and its bands) is fixed by the
	 * plan, so binning can also write every point that lies in another
	 * tile's first region to that tile's halo file: a tile's first run
	 * then reads its own file and its halo file once, without filtering,
	 * instead of every neighbour's file twice (counting, then filling).
	 * Per fine cell, the tiles whose first region meets the cell's box; a
	 * point is tested only against those.  Two files per tile: with too
	 * many tiles for the open files, every run gathers from the tile files.
	 */
	use_halo = nt <= 400;
	if (use_halo)
	{
		size_t		npairs = 0,
					cap = 1024;
		uint32_t   *pairs = malloc(sizeof(uint32_t) * 2 * cap);

		kfirst = malloc(32 * (size_t) (nt > 0 ? nt : 1));
		band_off = malloc(sizeof(size_t) * (nt + 1));
		cell_off = calloc((size_t) FINE_GRID * FINE_GRID + 1, sizeof(uint32_t));
		if (!pairs || !kfirst || !band_off || !cell_off)
			die(1, "out of memory%s", "");
		band_off[0] = 0;
		for (int t = 0; t < nt; t++)
		{
			double		h,
					   *K = kfirst + 4 * t;
			size_t		nb = 0;

			band_off[t + 1] = band_off[t];
			if (tiles[t].count == 0)
				continue;
			memset(inband, 0, nhull + 1);
			first_known(&tiles[t], xcut, ycut, bands, nhull, K, &h, inband);
			for (size_t i = 0; nhull > 1 && i < nhull; i++)
				if (inband[i])
					xs[nb++] = bands + 4 * i;
			band_idx = realloc(band_idx, sizeof(size_t) * (band_off[t] + nb + 1));
			if (band_idx == NULL)
				die(1, "out of memory%s", "");
			for (size_t i = 0; nhull > 1 && i < nhull; i++)
				if (inband[i])
					band_idx[band_off[t + 1]++] = i;
			/* the cells each box of the region meets, but the tile's own */
			for (size_t e = 0; e <= nb; e++)
			{
				const double *b = e == 0 ? K : xs[e - 1];
				int			c0 = cell_of(b[0], grid[0], sx, xcut),
							c1 = cell_of(b[2], grid[0], sx, xcut),
							r0 = cell_of(b[1], grid[1], sy, ycut),
							r1 = cell_of(b[3], grid[1], sy, ycut);

				if (b[2] < bb[0] || b[0] > bb[2] || b[3] < bb[1] || b[1] > bb[3])
					continue;
				for (int r = r0; r <= r1; r++)
					for (int c = c0; c <= c1; c++)
					{
						if (cell_tile[r * FINE_GRID + c] == t)
							continue;
						if (npairs == cap)
						{
							pairs = realloc(pairs, sizeof(uint32_t) * 2 * (cap *= 2));
							if (pairs == NULL)
								die(1, "out of memory%s", "");
						}
						pairs[2 * npairs] = (uint32_t) (r * FINE_GRID + c);
						pairs[2 * npairs + 1] = (uint32_t) t;
						npairs++;
					}
			}
		}
		/* per cell, its tiles (once each), as a counting sort by cell */
		{
			uint32_t   *fill;
			uint8_t    *seen = calloc((size_t) nt + 1, 1);

			for (size_t i = 0; i < npairs; i++)
				cell_off[pairs[2 * i] + 1]++;
			for (size_t c = 0; c < (size_t) FINE_GRID * FINE_GRID; c++)
				cell_off[c + 1] += cell_off[c];
			fill = malloc(sizeof(uint32_t) * ((size_t) FINE_GRID * FINE_GRID + 1));
			cell_halo = malloc(sizeof(int16_t) * (npairs + 1));
			if (!fill || !cell_halo || !seen)
				die(1, "out of memory%s", "");
			memcpy(fill, cell_off, sizeof(uint32_t) * ((size_t) FINE_GRID * FINE_GRID + 1));
			for (size_t i = 0; i < npairs; i++)
				cell_halo[fill[pairs[2 * i]]++] = (int16_t) pairs[2 * i + 1];
			/* drop repeats within a cell (a tile whose K and bands meet it) */
			for (size_t c = 0, at = 0; c < (size_t) FINE_GRID * FINE_GRID; c++)
			{
				uint32_t	a = cell_off[c],
							b = cell_off[c + 1];

				cell_off[c] = (uint32_t) at;
				for (uint32_t j = a; j < b; j++)
					if (!seen[cell_halo[j]])
					{
						seen[cell_halo[j]] = 1;
						cell_halo[at++] = cell_halo[j];
					}
				for (uint32_t j = cell_off[c]; j < at; j++)
					seen[cell_halo[j]] = 0;
				if (c + 1 == (size_t) FINE_GRID * FINE_GRID)
					cell_off[c + 1] = (uint32_t) at;
			}
			free(fill);
			free(seen);
			free(pairs);
		}
	}

	st->scan = now_s() - t0;

	/*
	 * 3: bin: every point to its tile's file, and to the halo files of the
	 * tiles whose first region holds it; two halves of the input on two
	 * threads (each with its own files) when there are file handles enough.
	 */
	t0 = now_s();
	nparts = n >= ((size_t) 1 << 18) && (size_t) nt * (use_halo ? 2 : 1) * 2 <= 800 ? 2 : 1;
	{
		/* buffers: a sixteenth of the budget over the files, 4 kB to 256 kB each */
		size_t		per = budget / 16 / (size_t) (2 * nparts * (nt > 0 ? nt : 1)) / 8;
		bin_work	bw[2];
		pthread_t	th;
		bool		started = false;

		per = per < 512 ? 512 : per > 32768 ? 32768 : per;
		for (int p = 0; p < nparts; p++)
		{
			bin_work   *b = &bw[p];

			b->xypath = xypath;
			b->zpath = zpath;
			b->grid = grid;
			b->xcut = xcut;
			b->ycut = ycut;
			b->kfirst = kfirst;
			b->bands = bands;
			b->sx = sx;
			b->sy = sy;
			b->cell_tile = cell_tile;
			b->cell_halo = cell_halo;
			b->cell_off = cell_off;
			b->band_off = band_off;
			b->band_idx = band_idx;
			b->use_halo = use_halo;
			b->w = w;
			b->nt = nt;
			b->from = n / nparts * p;
			b->count = p == nparts - 1 ? n - b->from : n / nparts;
			b->own = calloc((size_t) (nt > 0 ? nt : 1), sizeof(recfile));
			b->halo = use_halo ? calloc((size_t) (nt > 0 ? nt : 1), sizeof(recfile)) : NULL;
			b->bb = malloc(32 * (size_t) (nt > 0 ? nt : 1));
			if (b->own == NULL || (use_halo && b->halo == NULL) || b->bb == NULL)
				die(1, "out of memory%s", "");
			for (int t = 0; t < nt; t++)
			{
				b->bb[4 * t] = b->bb[4 * t + 1] = INFINITY;
				b->bb[4 * t + 2] = b->bb[4 * t + 3] = -INFINITY;
				rec_open(&b->own[t], "tile", t, p, per - per % w);
				if (use_halo)
					rec_open(&b->halo[t], "halo", t, p, (per / 4) - (per / 4) % (w + 1));
			}
		}
		if (nparts == 2)
			started = pthread_create(&th, NULL, bin_range, &bw[1]) == 0;
		bin_range(&bw[0]);
		if (started)
			pthread_join(th, NULL);
		else if (nparts == 2)
			bin_range(&bw[1]);
		halo_count = calloc((size_t) (nt > 0 ? nt : 1), sizeof(size_t));
		if (halo_count == NULL)
			die(1, "out of memory%s", "");
		for (int p = 0; p < nparts; p++)
		{
			for (int t = 0; t < nt; t++)
			{
				box_union2(tiles[t].bb, bw[p].bb + 4 * t);
				if (use_halo)
					halo_count[t] += bw[p].halo[t].count;
			}
			free(bw[p].own);
			free(bw[p].halo);
			free(bw[p].bb);
		}
	}
	free(cell_tile);
	free(cell_off);
	free(cell_halo);
	st->bin = now_s() - t0;

	/* 4: the tiles */
	for (int t = 0; t < nt; t++)
	{
		tile_info  *ti = &tiles[t];
		double		K[4],
					Kmin[4],	/* the least K this round may shrink back to */
					h;
		size_t		nextra = 0;
		tdc_tile_spec spec = {0};
		bool		first = use_halo;	/* the first run reads the tile and halo files */

		if (ti->count == 0)
			continue;			/* owns nothing */
		memset(inband, 0, nhull + 1);
		first_known(ti, xcut, ycut, bands, nhull, K, &h, inband);
		Kmin[0] = xcut[ti->c0];
		Kmin[1] = ycut[ti->r0];
		Kmin[2] = xcut[ti->c1];
		Kmin[3] = ycut[ti->r1];
		for (size_t i = 0; nhull > 1 && i < nhull; i++)
			if (inband[i])
				memcpy(extra + 4 * nextra++, bands + 4 * i, 32);
		spec.extra = extra;
		spec.nextra = nextra;
		spec.self = t;
		spec.hull = hull;
		spec.nhull = nhull;
		for (;;)
		{
			size_t		m = 0,
						at = 0;
			double	   *q = NULL,
					   *qz = NULL;
			int64_t    *ql = NULL;
			tdc_job    *job;
			tdc_tile_result res;
			tdc_times	tt;
			double		rec[4 * 4096];
			size_t		nx;

			int			shrinks = 0;

			t0 = now_s();
			if (first && tile_bytes(ti->count + halo_count[t], opt, has_z) > budget)
				first = false;
			if (first)
			{
				size_t		nh = halo_count[t];
				mreader		f;
				size_t		got;

				m = ti->count + nh;
				if (getenv("TDC_TILE_DEBUG"))
					fprintf(stderr, "tile %d/%d: own %zu, K %g %g %g %g: %zu points\n", t, nt,
							ti->count, K[0], K[1], K[2], K[3], m);
				q = malloc(16 * m + 16);
				ql = malloc(8 * m + 8);
				qz = has_z ? malloc(8 * m + 8) : NULL;
				if (!q || !ql || (has_z && !qz))
					die(1, "out of memory%s", "");
				if (!has_z)
					read_all("tile", t, nparts, q, ti->count, 2);
				else
				{
					mr_open(&f, "tile", t, nparts);
					while ((got = mr_read(&f, rec, 24, 4096)) > 0)
						for (size_t i = 0; i < got && at < ti->count; i++, at++)
						{
							q[2 * at] = rec[3 * i];
							q[2 * at + 1] = rec[3 * i + 1];
							qz[at] = rec[3 * i + 2];
						}
					mr_close(&f);
					if (at != ti->count)
						die(1, "short read on a temporary file in %s", tmp_dir);
				}
				for (size_t i = 0; i < ti->count; i++)
					ql[i] = t;
				at = ti->count;
				mr_open(&f, "halo", t, nparts);
				while ((got = mr_read(&f, rec, 8 * (size_t) (w + 1), 4096 * 4 / (w + 1))) > 0)
					for (size_t i = 0; i < got && at < m; i++, at++)
					{
						const double *p = rec + (w + 1) * i;

						q[2 * at] = p[0];
						q[2 * at + 1] = p[1];
						if (qz)
							qz[at] = p[2];
						ql[at] = (int64_t) p[w];
					}
				mr_close(&f);
				if (at != m)
					die(1, "short read on a temporary file in %s", tmp_dir);
				if (getenv("TDC_TILE_CHECK") && count_known(tiles, nt, nparts, K, extra, nextra, w) != m)
				{
					char		msg[160];

					snprintf(msg, sizeof(msg), "tile %d: %zu points in its files, %zu in its first region",
							 t, m, count_known(tiles, nt, nparts, K, extra, nextra, w));
					die(1, "TDC_TILE_CHECK: %s", msg);
				}
				first = false;
			}
			else
				/* count, then fill: the buffers are allocated once, at their size */
				for (int pass = 0; pass < 2; pass++)
				{
					for (int u = -1; u < nt; u++)
					{
						int			s = u < 0 ? t : u;
						mreader		f;
						size_t		got;

						bool		meets = box_meets(tiles[s].bb, K);

						for (size_t e = 0; e < nextra && !meets; e++)
							meets = box_meets(tiles[s].bb, extra + 4 * e);
						if ((u >= 0 && u == t) || tiles[s].count == 0 || !meets)
							continue;
						/* only the bands that meet this file's box need testing */
						nx = 0;
						for (size_t e = 0; e < nextra; e++)
							if (box_meets(tiles[s].bb, extra + 4 * e))
								xs[nx++] = extra + 4 * e;
						mr_open(&f, "tile", s, nparts);
						while ((got = mr_read(&f, rec, 8 * (size_t) w, 4096)) > 0)
							for (size_t i = 0; i < got; i++)
							{
								double	   *p = rec + w * i;

								bool		in = p[0] >= K[0] && p[0] <= K[2] &&
									p[1] >= K[1] && p[1] <= K[3];

								for (size_t e = 0; e < nx && !in; e++)
								{
									const double *x = xs[e];

									in = p[0] >= x[0] && p[0] <= x[2] && p[1] >= x[1] && p[1] <= x[3];
								}
								if (!in)
									continue;
								if (pass == 1)
								{
									q[2 * at] = p[0];
									q[2 * at + 1] = p[1];
									if (qz)
										qz[at] = p[2];
									ql[at] = s;
									at++;
								}
								else
									m++;
							}
						mr_close(&f);
					}
					if (pass == 0 && getenv("TDC_TILE_DEBUG"))
						fprintf(stderr, "tile %d/%d: own %zu, K %g %g %g %g: %zu points\n", t, nt,
								ti->count, K[0], K[1], K[2], K[3], m);
					if (pass == 0)
					{
						if (tile_bytes(m, opt, has_z) > budget && shrinks < 4 &&
							memcmp(K, Kmin, sizeof(K)) != 0)
						{
							/*
							 * The halo (or the slack of a grown box) reaches
							 * into denser data than the tile's: shrink it
							 * towards the least box, the finality test will
							 * ask for what is really needed.
							 */
							for (int c = 0; c < 4; c++)
								K[c] = shrinks == 3 ? Kmin[c] : Kmin[c] + (K[c] - Kmin[c]) / 4;
							shrinks++;
							m = 0;
							pass = -1;
							continue;
						}
						if (tile_bytes(m, opt, has_z) > budget)
						{
							char		msg[160];

							snprintf(msg, sizeof(msg), "tile %d needs %zu points with its halo, about %zu MB",
									 t, m, tile_bytes(m, opt, has_z) >> 20);
							die(1, "%s: more than --max-memory allows (the data is too clustered or the limit too small)", msg);
						}
						q = malloc(16 * m + 16);
						ql = malloc(8 * m + 8);
						qz = has_z ? malloc(8 * m + 8) : NULL;
						if (!q || !ql || (has_z && !qz))
							die(1, "out of memory%s", "");
					}
				}
			memcpy(spec.known, K, sizeof(K));
			spec.tile = ql;
			st->runs++;
			st->gather += now_s() - t0;
			t0 = now_s();
			if (tdc_triangulate(q, m, opt, &job, err, sizeof(err)) != TDC_OK)
				die(1, "%s", err);
			st->engine += now_s() - t0;
			t0 = now_s();
			if (tdc_tile_finish(job, &spec, &res, err, sizeof(err)) != TDC_OK)
				die(1, "%s", err);
			st->finish += now_s() - t0;
			t0 = now_s();
			tdc_job_times(job, &tt);
			st->t.sort += tt.sort;
			st->t.subdivide += tt.subdivide;
			st->t.leaves += tt.leaves;
			st->t.merge += tt.merge;
			st->threads = tdc_threads_used(job);
			tdc_job_free(job);
			if (res.final)
			{
				for (size_t j = 0; out && j < res.ntri; j++)
					write_tri(out, q, qz, res.tri + 3 * j);
				st->ntri += res.ntri;
				st->unique += res.own_sites;
				st->halo += m - ti->count;
			}
			else
			{
				/* grow a little more than asked: each run costs a whole tile */
				double		gx = 0.5 * h,
							gy = 0.5 * h;
				size_t		added = 0;

				/*
				 * A request reaching along the border comes from slivers
				 * under a long hull edge, whose circles' parts inside C are
				 * thin lenses along the hull: first add the bands of the
				 * hull edges the request meets and run again with the same
				 * K, rather than widen K along the whole side.
				 */
				for (size_t i = 0; nhull > 1 && i < nhull; i++)
					if (!inband[i] && box_meets(bands + 4 * i, res.need))
					{
						inband[i] = 1;
						memcpy(extra + 4 * nextra++, bands + 4 * i, 32);
						added++;
					}
				if (added > 0)
				{
					spec.nextra = nextra;
					tdc_tile_result_free(&res);
					free(q);
					free(ql);
					free(qz);
					continue;
				}

				/*
				 * If need is too big for the budget, K may fall back to a
				 * step of an eighth of the way from the old K: the needs of
				 * a thin halo overstate what the final stars need, and any
				 * growth is progress.
				 */
				for (int c = 0; c < 4; c++)
					Kmin[c] = K[c] + (res.need[c] - K[c]) / 8;
				K[0] = res.need[0] - gx;
				K[1] = res.need[1] - gy;
				K[2] = res.need[2] + gx;
				K[3] = res.need[3] + gy;
			}
			tdc_tile_result_free(&res);
			free(q);
			free(ql);
			free(qz);
			st->write += now_s() - t0;
			if (spec.known[0] == K[0] && spec.known[1] == K[1] &&
				spec.known[2] == K[2] && spec.known[3] == K[3])
				break;			/* final: K was not changed */
		}
	}
	free(extra);
	free(bands);
	free(inband);
	free(xs);
	free(tiles);
	free(hull);
	free(kfirst);
	free(band_off);
	free(band_idx);
	free(halo_count);
}
