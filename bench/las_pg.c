/*
 * las_pg.c
 *		The points of one class of a LAS file as rows for PostgreSQL's COPY:
 *		geometries or pgpointcloud patches, for bench/coverage_bench.sh.
 *
 *	las_pg info LAS CLASS
 *	las_pg geom LAS CLASS SRID
 *	las_pg patch LAS CLASS PCID SIDE
 *
 * Loading 1e8 points through SQL functions (ST_MakePoint, or PC_MakePoint
 * and the PC_Patch aggregate) takes longer than what the benchmark times,
 * so the rows are written here in the types' own input forms and COPY reads
 * them: COPY's text format, one row a line.
 *
 * geom: one column, the hex EWKB of a POINT Z with the SRID (little endian:
 * byte order 1, type 0xA0000001 = point | Z flag | SRID flag, the SRID,
 * then x, y, z as doubles).  Each coordinate is the LAS record's int32 times
 * the header's scale plus its offset, in double, as ./tdc's LAS reader
 * (src/cli/las.c) and pgpointcloud (value * scale + offset) compute it, so
 * the table holds the very doubles the command line triangulates.
 *
 * patch: two columns, a patch number from 1 and the hex WKB of an
 * uncompressed pgpointcloud patch, the format of pgpointcloud's README:
 * byte order 1, pcid uint32, compression uint32 (0: none), npoints uint32,
 * then each point's dimensions in schema order, here X, Y, Z as the LAS
 * file's raw int32 (so the schema must declare int32_t X, Y, Z with the LAS
 * header's scales and offsets, which `info` prints).  The patches are
 * spatially coherent, as a chipper makes them: the squares of SIDE metres
 * of a grid from the header's minimum X and Y, each square's points in file
 * order.  A LAS file written in swaths (bench/gen_las.c writes rows from
 * south to north) is read once, band of squares by band: a band is written
 * when the points have moved two bands past it, so memory holds a few bands,
 * not the file.  A point that comes back to a band already written is an
 * error: the file is not in rows.  The order of two points with the same x
 * and y is the file's in every output, so the first copy of a duplicate is
 * the same one for every reader.
 *
 * info: "key=value" words on one line: the count of points of the class,
 * their box (x0 y0 x1 y1, the doubles), and the header's scale and offset
 * of X, Y and Z (%.17g).
 *
 * The LAS fields read: header size (94), offset to the points (96), point
 * format (104, low 6 bits), record length (105), the legacy (107) and the
 * 1.4 (247) point counts, scales (131), offsets (155), minimum X (187) and Y
 * (203); per record X, Y, Z as int32 at 0, 4, 8 and the classification in
 * byte 15's low 5 bits (formats 0-5) or byte 16 (6-10).
 *
 * Build: cc -O2 -o build/las_pg bench/las_pg.c (bench/lib.sh, build_helpers)
 */
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct las
{
	FILE	   *f;
	const char *path;
	uint64_t	n;				/* records */
	unsigned	reclen;
	unsigned	format;
	double		scale[3],
				offset[3],
				minx,
				miny;
} las;

typedef struct pt
{
	int32_t		raw[3];
	int32_t		col;			/* the square's column in its band */
} pt;

/* a band of squares: its points as they came */
typedef struct band
{
	int64_t		index;			/* -1: unused */
	pt		   *p;
	size_t		n,
				cap;
} band;

#define NBANDS 4
static const char hexd[] = "0123456789ABCDEF";

static void
die(const char *fmt,...)
{
	va_list		ap;

	va_start(ap, fmt);
	fputs("las_pg: ", stderr);
	vfprintf(stderr, fmt, ap);
	fputc('\n', stderr);
	va_end(ap);
	exit(1);
}

static uint32_t
le32(const unsigned char *b)
{
	return (uint32_t) b[0] | (uint32_t) b[1] << 8 | (uint32_t) b[2] << 16 | (uint32_t) b[3] << 24;
}

static double
led(const unsigned char *b)
{
	uint64_t	u = (uint64_t) le32(b) | (uint64_t) le32(b + 4) << 32;
	double		d;

	memcpy(&d, &u, 8);
	return d;
}

static void
las_open(las *l, const char *path)
{
	unsigned char h[375];
	unsigned	hsize;
	uint32_t	off;

	memset(l, 0, sizeof(*l));
	l->path = path;
	l->f = fopen(path, "rb");
	if (!l->f)
		die("%s: %s", path, strerror(errno));
	if (fread(h, 1, 227, l->f) != 227 || memcmp(h, "LASF", 4) != 0)
		die("%s: not a LAS file (no LASF header)", path);
	hsize = h[94] | h[95] << 8;
	if (hsize >= 375 && fread(h + 227, 1, 375 - 227, l->f) != 375 - 227)
		die("%s: the header ends early", path);
	off = le32(h + 96);
	l->format = h[104] & 0x3f;
	l->reclen = h[105] | h[106] << 8;
	if (l->format > 10 || l->reclen < (l->format >= 6 ? 17u : 16u))
		die("%s: point format %u with %u-byte records is not read here", path, l->format, l->reclen);
	l->n = le32(h + 107);
	if (h[25] >= 4 && hsize >= 375)
	{
		uint64_t	n64 = (uint64_t) le32(h + 247) | (uint64_t) le32(h + 251) << 32;

		if (n64 != 0)
			l->n = n64;
	}
	for (int c = 0; c < 3; c++)
	{
		l->scale[c] = led(h + 131 + 8 * c);
		l->offset[c] = led(h + 155 + 8 * c);
	}
	l->minx = led(h + 187);
	l->miny = led(h + 203);
	if (fseek(l->f, off, SEEK_SET) != 0)
		die("%s: cannot seek to its points (offset %u)", path, off);
}

/* the next record of the class into raw; 0 at the end */
static int
las_next(las *l, unsigned cls, int32_t raw[3], unsigned char *rec)
{
	while (l->n > 0)
	{
		unsigned	c;

		l->n--;
		if (fread(rec, 1, l->reclen, l->f) != l->reclen)
			die("%s: the points end early", l->path);
		c = l->format >= 6 ? rec[16] : (rec[15] & 31u);
		if (c != cls)
			continue;
		for (int k = 0; k < 3; k++)
			raw[k] = (int32_t) le32(rec + 4 * k);
		return 1;
	}
	return 0;
}

static double
coord(const las *l, int c, int32_t raw)
{
	double		v = (double) raw * l->scale[c];

	return v + l->offset[c];
}

static void
hex(const void *buf, size_t n, FILE *out)
{
	const unsigned char *b = buf;

	for (size_t i = 0; i < n; i++)
	{
		putc(hexd[b[i] >> 4], out);
		putc(hexd[b[i] & 15], out);
	}
}

static void
put32(unsigned char *b, uint32_t v)
{
	for (int i = 0; i < 4; i++)
		b[i] = (unsigned char) (v >> (8 * i));
}

static void
putd(unsigned char *b, double d)
{
	uint64_t	u;

	memcpy(&u, &d, 8);
	put32(b, (uint32_t) u);
	put32(b + 4, (uint32_t) (u >> 32));
}

/* the squares of one band as patches, each square's points in file order */
static void
flush_band(band *b, uint32_t pcid, uint64_t *id, FILE *out)
{
	int32_t		maxcol = -1;
	size_t	   *start;
	pt		   *sorted;
	unsigned char h[13],
				v[12];

	if (b->n == 0)
	{
		b->index = -1;
		return;
	}
	for (size_t i = 0; i < b->n; i++)
		if (b->p[i].col > maxcol)
			maxcol = b->p[i].col;
	/* a stable counting sort by column */
	start = calloc((size_t) maxcol + 2, sizeof(size_t));
	sorted = malloc(b->n * sizeof(pt));
	if (!start || !sorted)
		die("out of memory sorting a band of %zu points", b->n);
	for (size_t i = 0; i < b->n; i++)
		start[b->p[i].col + 1]++;
	for (int32_t c = 0; c <= maxcol; c++)
		start[c + 1] += start[c];
	for (size_t i = 0; i < b->n; i++)
		sorted[start[b->p[i].col]++] = b->p[i];
	for (size_t i = 0; i < b->n;)
	{
		size_t		j = i;

		while (j < b->n && sorted[j].col == sorted[i].col)
			j++;
		h[0] = 1;
		put32(h + 1, pcid);
		put32(h + 5, 0);
		put32(h + 9, (uint32_t) (j - i));
		fprintf(out, "%llu\t", (unsigned long long) ++*id);
		hex(h, sizeof(h), out);
		for (; i < j; i++)
		{
			for (int k = 0; k < 3; k++)
				put32(v + 4 * k, (uint32_t) sorted[i].raw[k]);
			hex(v, sizeof(v), out);
		}
		putc('\n', out);
	}
	free(start);
	free(sorted);
	b->n = 0;
	b->index = -1;
}

static void
patches(las *l, unsigned cls, uint32_t pcid, double side, FILE *out)
{
	band		bands[NBANDS];
	int64_t		written = -1;	/* bands up to this one are written */
	uint64_t	id = 0;
	int32_t		raw[3];
	unsigned char *rec = malloc(l->reclen);

	if (!rec)
		die("out of memory");
	for (int i = 0; i < NBANDS; i++)
		bands[i] = (band) {-1, NULL, 0, 0};
	while (las_next(l, cls, raw, rec))
	{
		double		x = coord(l, 0, raw[0]),
					y = coord(l, 1, raw[1]);
		int64_t		bi = (int64_t) floor((y - l->miny) / side);
		int64_t		col = (int64_t) floor((x - l->minx) / side);
		band	   *b;

		if (bi < 0 || col < 0 || col > INT32_MAX - 2)
			die("%s: point (%.17g %.17g) outside the header's box", l->path, x, y);
		if (bi <= written)
			die("%s: a point of band %lld after that band was written: the points are not in rows from south to north",
				l->path, (long long) bi);
		/* the bands two behind this one are complete */
		for (int i = 0; i < NBANDS; i++)
			if (bands[i].index >= 0 && bands[i].index <= bi - 2)
			{
				if (bands[i].index > written)
					written = bands[i].index;
				flush_band(&bands[i], pcid, &id, out);
			}
		b = &bands[bi % NBANDS];
		if (b->index != bi)
		{
			if (b->index >= 0)
				die("%s: band %lld and band %lld at once: the points are not in rows", l->path,
					(long long) b->index, (long long) bi);
			b->index = bi;
		}
		if (b->n == b->cap)
		{
			b->cap = b->cap ? 2 * b->cap : 65536;
			b->p = realloc(b->p, b->cap * sizeof(pt));
			if (!b->p)
				die("out of memory: a band of %zu points", b->n);
		}
		memcpy(b->p[b->n].raw, raw, sizeof(raw));
		b->p[b->n].col = (int32_t) col;
		b->n++;
	}
	/* the last bands, south to north */
	for (;;)
	{
		band	   *lo = NULL;

		for (int i = 0; i < NBANDS; i++)
			if (bands[i].index >= 0 && (!lo || bands[i].index < lo->index))
				lo = &bands[i];
		if (!lo)
			break;
		flush_band(lo, pcid, &id, out);
	}
	for (int i = 0; i < NBANDS; i++)
		free(bands[i].p);
	free(rec);
}

static void
geoms(las *l, unsigned cls, uint32_t srid, FILE *out)
{
	unsigned char w[33];
	int32_t		raw[3];
	unsigned char *rec = malloc(l->reclen);

	if (!rec)
		die("out of memory");
	w[0] = 1;
	put32(w + 1, 0xA0000001u);
	put32(w + 5, srid);
	while (las_next(l, cls, raw, rec))
	{
		for (int k = 0; k < 3; k++)
			putd(w + 9 + 8 * k, coord(l, k, raw[k]));
		hex(w, sizeof(w), out);
		putc('\n', out);
	}
	free(rec);
}

static void
info(las *l, unsigned cls)
{
	int32_t		raw[3];
	uint64_t	n = 0;
	double		x0 = INFINITY,
				y0 = INFINITY,
				x1 = -INFINITY,
				y1 = -INFINITY;
	unsigned char *rec = malloc(l->reclen);

	if (!rec)
		die("out of memory");
	while (las_next(l, cls, raw, rec))
	{
		double		x = coord(l, 0, raw[0]),
					y = coord(l, 1, raw[1]);

		n++;
		x0 = fmin(x0, x);
		x1 = fmax(x1, x);
		y0 = fmin(y0, y);
		y1 = fmax(y1, y);
	}
	printf("n=%llu x0=%.17g y0=%.17g x1=%.17g y1=%.17g", (unsigned long long) n, x0, y0, x1, y1);
	for (int c = 0; c < 3; c++)
		printf(" scale%c=%.17g offset%c=%.17g", "xyz"[c], l->scale[c], "xyz"[c], l->offset[c]);
	putchar('\n');
	free(rec);
}

static unsigned long
num(const char *s, const char *what, unsigned long max)
{
	char	   *end;
	unsigned long v;

	errno = 0;
	v = strtoul(s, &end, 10);
	if (errno || *end || end == s || v > max)
		die("%s must be a whole number up to %lu, not '%s'", what, max, s);
	return v;
}

int
main(int argc, char **argv)
{
	las			l;
	unsigned	cls;
	static char buf[1 << 20];

	if (argc < 4)
		die("usage: las_pg info LAS CLASS | geom LAS CLASS SRID | patch LAS CLASS PCID SIDE");
	cls = (unsigned) num(argv[3], "CLASS", 255);
	setvbuf(stdout, buf, _IOFBF, sizeof(buf));
	las_open(&l, argv[2]);
	if (strcmp(argv[1], "info") == 0 && argc == 4)
		info(&l, cls);
	else if (strcmp(argv[1], "geom") == 0 && argc == 5)
		geoms(&l, cls, (uint32_t) num(argv[4], "SRID", 999999), stdout);
	else if (strcmp(argv[1], "patch") == 0 && argc == 6)
	{
		double		side = atof(argv[5]);

		if (!(side > 0))
			die("SIDE must be a positive number of metres, not '%s'", argv[5]);
		patches(&l, cls, (uint32_t) num(argv[4], "PCID", UINT32_MAX), side, stdout);
	}
	else
		die("usage: las_pg info LAS CLASS | geom LAS CLASS SRID | patch LAS CLASS PCID SIDE");
	if (fflush(stdout) != 0 || ferror(stdout))
		die("cannot write the output: %s", strerror(errno));
	fclose(l.f);
	return 0;
}
