/*
 * las.c
 *		INPUT as an ASPRS LAS file: versions 1.2 to 1.4, uncompressed,
 *		point data record formats 0 to 10, its points streamed in batches of
 *		whole records; its coordinate reference system as a string.
 *
 * Written from the specification, "LAS Specification 1.4 - R15" (ASPRS,
 * 9 July 2019); the section numbers below are that document's.  LAS is
 * little-endian throughout (§2): every field is decoded byte by byte here,
 * so the reader does not depend on the machine's byte order.
 *
 * The file (§2): a public header block, the variable length records
 * (VLRs), the point data records, and in 1.4 the extended VLRs (EVLRs)
 * after the points.  The header (§2.4) is 227 bytes in 1.2, 235 in 1.3
 * (+ the start of the waveform data) and 375 in 1.4 (+ the first EVLR's
 * offset, the number of EVLRs, and 64-bit point counts).  The fields read:
 *
 *	  0 signature "LASF"			 24 version major, minor
 *	  6 global encoding (bit 4: WKT)	 94 header size
 *	 96 offset to point data (u32)	100 number of VLRs (u32)
 *	104 point data record format	105 point data record length (u16)
 *	107 legacy number of points (u32)	131 X Y Z scale, 155 X Y Z offset (f64)
 *	235 start of first EVLR (u64)	243 number of EVLRs (u32)
 *	247 number of points (u64)
 *
 * Everything the points depend on is checked before the first point is
 * read, and before any output is opened: the signature, the version, the
 * format (bit 7 of the format byte is LASzip's mark of a compressed file,
 * bit 6 that of an older compressor; LASzip also adds its own VLR, user
 * "laszip encoded", record 22204: both refused by name), the record length
 * (it may exceed the format's size, §2.4: the rest are "extra bytes",
 * skipped; it may not be shorter), the VLRs inside the space before the
 * points, the points inside the file, the EVLRs inside it.  A truncated
 * file is found from its size, not halfway through a run.
 *
 * The number of points: 1.4's 64-bit count, which "must always be
 * correctly populated" (§2.4); when it is 0, or before 1.4, the legacy
 * 32-bit count (which 1.4 writers set to 0 for formats 6 to 10).
 *
 * A point (§2.6): X, Y, Z as int32 at bytes 0, 4, 8 in every format; the
 * coordinate is X * scale + offset (§2.4), in double, the expression every
 * LAS reader evaluates, so that ./tdc's x y z are another reader's to the
 * bit (test/cli_las.sh checks it against loaders.gl).  The classification:
 * formats 0 to 5 (minimum sizes 20 28 26 34 57 63 bytes) keep it in the low
 * 5 bits of byte 15, whose high bits are the synthetic, key-point and
 * withheld flags; formats 6 to 10 (30 36 38 59 67 bytes) in the whole byte
 * 16.  --class keeps the listed values; the flags are not read (a withheld
 * point is kept).  The point layouts do not depend on the version, so a
 * format the version does not define (6 in a 1.2 file) is read all the same.
 *
 * The CRS (§2.2, §3): the WKT bit of the global encoding says whether the
 * file's CRS is WKT (user "LASF_Projection", record 2112, a null-terminated
 * string, in a VLR or an EVLR) or GeoTIFF (record 34735, the GeoKey
 * directory: 4 u16 of header, the last the number of keys, then 4 u16 per
 * key: id, location, count, value).  From the GeoKeys only an EPSG code is
 * taken: ProjectedCSTypeGeoKey (3072) or else GeographicTypeGeoKey (2048),
 * stored in the directory itself (location 0), 1 to 32766 (32767 is
 * "user-defined": no code).  When the kind the bit names is absent, the
 * other is taken.  Two records of a kind are a file error (§2.2); the last
 * one read wins, so an EVLR appended later replaces a VLR.  A superseded
 * record (LASF_Spec 7) no longer carries the ids and is not read.
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "cli.h"

/* The minimum record size of each point data record format (§2.6) */
static const unsigned format_size[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

/* The read buffer: whole records, at least one */
#define LAS_BUFFER_BYTES ((size_t) 1 << 20)

/* A WKT longer than this is not a CRS */
#define LAS_WKT_MAX ((uint64_t) 1 << 20)

static uint16_t
le16(const unsigned char *p)
{
	return (uint16_t) (p[0] | p[1] << 8);
}

static uint32_t
le32(const unsigned char *p)
{
	return (uint32_t) p[0] | (uint32_t) p[1] << 8 | (uint32_t) p[2] << 16 | (uint32_t) p[3] << 24;
}

static uint64_t
le64(const unsigned char *p)
{
	return (uint64_t) le32(p) | (uint64_t) le32(p + 4) << 32;
}

static double
ledouble(const unsigned char *p)
{
	uint64_t	u = le64(p);
	double		d;

	memcpy(&d, &u, 8);
	return d;
}

/* "tdc: PATH: reason" and exit 1 */
static void las_fail(const las_file *lf, const char *fmt,...) __attribute__((noreturn, format(printf, 2, 3)));

static void
las_fail(const las_file *lf, const char *fmt,...)
{
	char		msg[8192];
	va_list		ap;
	int			k = snprintf(msg, sizeof(msg) / 2, "%s: ", lf->path);

	/* a path too long for its half is cut there, and the reason still fits */
	if (k < 0 || k >= (int) sizeof(msg) / 2)
		k = (int) strlen(msg);
	va_start(ap, fmt);
	vsnprintf(msg + k, sizeof(msg) - k, fmt, ap);
	va_end(ap);
	die(1, "%s", msg);
}

/* Whether INPUT is read as LAS: a name ending in .las or .laz, any case (LAZ is refused inside) */
bool
is_las_path(const char *path)
{
	size_t		n = strlen(path);

	return n >= 4 && (strcasecmp(path + n - 4, ".las") == 0 || strcasecmp(path + n - 4, ".laz") == 0);
}

/*
 * --class LIST: comma-separated classification values 0 to 255 into
 * keep[].  Dies (exit 2) on anything else.
 */
void
las_parse_classes(const char *list, unsigned char keep[256])
{
	const char *p = list;

	memset(keep, 0, 256);
	for (;;)
	{
		char	   *end;
		long		v;

		if (*p < '0' || *p > '9')
			die(2, "invalid value for --class (comma-separated classification values 0 to 255): %s", list);
		v = strtol(p, &end, 10);
		if (v > 255)
			die(2, "invalid value for --class (comma-separated classification values 0 to 255): %s", list);
		keep[v] = 1;
		if (*end == '\0')
			return;
		if (*end != ',')
			die(2, "invalid value for --class (comma-separated classification values 0 to 255): %s", list);
		p = end + 1;
	}
}

/* n bytes at offset into buf, or false when the file ends first */
static bool
read_at(las_file *lf, uint64_t offset, void *buf, size_t n)
{
	if (fseeko(lf->f, (off_t) offset, SEEK_SET) != 0)
		return false;
	return fread(buf, 1, n, lf->f) == n;
}

/* The payload of a WKT record: its string up to the first NUL, or NULL when empty */
static char *
read_wkt(las_file *lf, uint64_t offset, uint64_t len, const char *what, unsigned k)
{
	char	   *s;

	if (len > LAS_WKT_MAX)
		las_fail(lf, "the WKT of %s %u has %llu bytes, more than a CRS needs (%llu)",
				 what, k, (unsigned long long) len, (unsigned long long) LAS_WKT_MAX);
	s = malloc(len + 1);
	if (s == NULL)
		las_fail(lf, "out of memory for the WKT of %s %u", what, k);
	if (!read_at(lf, offset, s, len))
		las_fail(lf, "truncated: the WKT of %s %u runs past the end of the file", what, k);
	s[len] = '\0';
	if (s[0] == '\0')
	{
		free(s);
		return NULL;
	}
	return s;
}

/* The value of GeoKey id stored in the directory itself (location 0), or -1 */
static int
geokey(const unsigned char *d, unsigned nkeys, unsigned id)
{
	for (unsigned i = 0; i < nkeys; i++)
	{
		const unsigned char *e = d + 8 + 8 * i;

		if (le16(e) == id && le16(e + 2) == 0)
			return le16(e + 6);
	}
	return -1;
}

/*
 * The EPSG code of a GeoKey directory (record 34735) as "EPSG:N", or
 * NULL: ProjectedCSTypeGeoKey, else (absent or 0, "undefined")
 * GeographicTypeGeoKey; a user-defined one (32767) has no code.
 */
static char *
read_geokeys(las_file *lf, uint64_t offset, uint64_t len, const char *what, unsigned k)
{
	unsigned char *d;
	unsigned	nkeys = 0;
	int			code;
	char	   *s;

	if (len > 65535 * 8 + 8)
		las_fail(lf, "the GeoKey directory of %s %u has %llu bytes, more than 65535 keys", what, k,
				 (unsigned long long) len);
	d = malloc(len + 1);
	if (d == NULL)
		las_fail(lf, "out of memory for the GeoKey directory of %s %u", what, k);
	if (!read_at(lf, offset, d, len))
		las_fail(lf, "truncated: the GeoKey directory of %s %u runs past the end of the file", what, k);
	if (len < 8 || len < 8 + 8 * (uint64_t) (nkeys = le16(d + 6)))
		las_fail(lf, "the GeoKey directory of %s %u (%llu bytes) is shorter than its header and %u keys",
				 what, k, (unsigned long long) len, nkeys);
	code = geokey(d, nkeys, 3072);
	if (code <= 0)
		code = geokey(d, nkeys, 2048);
	free(d);
	if (code <= 0 || code >= 32767)
		return NULL;
	s = malloc(16);
	if (s == NULL)
		las_fail(lf, "out of memory for the GeoKey directory of %s %u", what, k);
	snprintf(s, 16, "EPSG:%d", code);
	return s;
}

/*
 * One VLR's (evlr false) or EVLR's header at *pos (54 or 60 bytes): the
 * CRS records kept in wkt / geo, LAZ refused; *pos moved past its payload.
 */
static void
read_record(las_file *lf, uint64_t *pos, bool evlr, unsigned k, char **wkt, char **geo)
{
	unsigned char h[60];
	size_t		hlen = evlr ? 60 : 54;
	const char *what = evlr ? "extended variable length record" : "variable length record";
	char		user[17];
	unsigned	id;
	uint64_t	len;

	if (!read_at(lf, *pos, h, hlen))
		las_fail(lf, "truncated: %s %u runs past the end of the file", what, k);
	memcpy(user, h + 2, 16);
	user[16] = '\0';
	id = le16(h + 18);
	len = evlr ? le64(h + 20) : le16(h + 20);
	if (len > lf->size || *pos + hlen > lf->size - len)
		las_fail(lf, "truncated: %s %u (%llu bytes after its header) runs past the end of the file",
				 what, k, (unsigned long long) len);
	if (strcmp(user, "laszip encoded") == 0 && id == 22204)
		las_fail(lf, "a LAZ (compressed LAS) file (it has LASzip's VLR): not read; decompress it to .las first");
	if (strcmp(user, "LASF_Projection") == 0 && (id == 2112 || id == 34735))
	{
		char	   *s = id == 2112 ? read_wkt(lf, *pos + hlen, len, what, k) :
			read_geokeys(lf, *pos + hlen, len, what, k);
		char	  **slot = id == 2112 ? wkt : geo;

		if (s)
		{
			free(*slot);
			*slot = s;
		}
	}
	*pos += hlen + len;
}

/*
 * Open path, check everything the points depend on (see the top of the
 * file), take its CRS, and stand before the first point.  Dies with the
 * file's name and the reason.
 */
void
las_open(const char *path, las_file *lf)
{
	unsigned char h[375];
	size_t		got,
				need;
	struct stat sb;
	unsigned	hsize,
				nvlr,
				fmt_byte;
	uint64_t	pos,
				room;
	char	   *wkt = NULL,
			   *geo = NULL;

	memset(lf, 0, sizeof(*lf));
	lf->path = path;
	lf->f = fopen(path, "rb");
	if (lf->f == NULL)
		die(1, "cannot open %s", path);
	if (fstat(fileno(lf->f), &sb) != 0 || !S_ISREG(sb.st_mode))
		las_fail(lf, "not a regular file (a LAS file is read by offsets)");
	lf->size = (uint64_t) sb.st_size;
	got = fread(h, 1, sizeof(h), lf->f);
	if (got < 4 || memcmp(h, "LASF", 4) != 0)
		las_fail(lf, "not a LAS file (no \"LASF\" signature)");
	if (got < 227)
		las_fail(lf, "truncated header: %zu bytes, LAS 1.2's header has 227", got);
	fmt_byte = h[104];
	if (fmt_byte & 0xC0)
		las_fail(lf, "a LAZ (compressed LAS) file (bit %d of its point format byte %u): not read; decompress it to .las first",
				 fmt_byte & 0x80 ? 7 : 6, fmt_byte);
	lf->major = h[24];
	lf->minor = h[25];
	if (lf->major != 1 || lf->minor < 2 || lf->minor > 4)
		las_fail(lf, "LAS version %d.%d is not read (1.2 to 1.4 are)", lf->major, lf->minor);
	need = lf->minor == 2 ? 227 : lf->minor == 3 ? 235 : 375;
	if (got < need)
		las_fail(lf, "truncated header: %zu bytes, LAS 1.%d's header has %zu", got, lf->minor, need);
	hsize = le16(h + 94);
	if (hsize < need)
		las_fail(lf, "its header size field says %u bytes, LAS 1.%d's header has %zu", hsize, lf->minor, need);
	lf->format = (int) fmt_byte;
	if (lf->format > 10)
		las_fail(lf, "point data record format %d is not read (0 to 10 are)", lf->format);
	lf->reclen = le16(h + 105);
	if (lf->reclen < format_size[lf->format])
		las_fail(lf, "point data record length %u is shorter than format %d's %u bytes",
				 lf->reclen, lf->format, format_size[lf->format]);
	lf->global_encoding = le16(h + 6);
	lf->point_offset = le32(h + 96);
	if (lf->point_offset < hsize)
		las_fail(lf, "the offset to the point data (%llu) lies inside the %u-byte header",
				 (unsigned long long) lf->point_offset, hsize);
	lf->n = le32(h + 107);
	if (lf->minor >= 4 && le64(h + 247) != 0)
		lf->n = le64(h + 247);
	for (int c = 0; c < 3; c++)
	{
		lf->scale[c] = ledouble(h + 131 + 8 * c);
		lf->offset[c] = ledouble(h + 155 + 8 * c);
		if (!isfinite(lf->scale[c]) || lf->scale[c] == 0 || !isfinite(lf->offset[c]))
			las_fail(lf, "its %c scale factor (%g) or offset (%g) is not a finite number (nor 0 for the scale)",
					 "XYZ"[c], lf->scale[c], lf->offset[c]);
	}

	/* the VLRs, between the header and the points */
	nvlr = le32(h + 100);
	pos = hsize;
	for (unsigned k = 0; k < nvlr; k++)
	{
		read_record(lf, &pos, false, k, &wkt, &geo);
		if (pos > lf->point_offset)
			las_fail(lf, "variable length record %u ends at byte %llu, past the offset to the point data (%llu)",
					 k, (unsigned long long) pos, (unsigned long long) lf->point_offset);
	}

	/* the points, inside the file */
	room = lf->size > lf->point_offset ? lf->size - lf->point_offset : 0;
	if (lf->n > room / lf->reclen)
		las_fail(lf, "truncated: the header says %llu points of %u bytes from byte %llu, the file has %llu bytes",
				 (unsigned long long) lf->n, lf->reclen, (unsigned long long) lf->point_offset,
				 (unsigned long long) lf->size);

	/* 1.4: the EVLRs, after the points */
	if (lf->minor >= 4 && le32(h + 243) > 0)
	{
		unsigned	nevlr = le32(h + 243);

		pos = le64(h + 235);
		if (pos < lf->point_offset + lf->n * lf->reclen)
			las_fail(lf, "the first extended variable length record (byte %llu) lies before the end of the points",
					 (unsigned long long) pos);
		for (unsigned k = 0; k < nevlr; k++)
			read_record(lf, &pos, true, k, &wkt, &geo);
	}

	/* the CRS the WKT bit names, else the other */
	if ((lf->global_encoding & 16) ? wkt != NULL : geo == NULL)
	{
		lf->srs = wkt;
		free(geo);
	}
	else
	{
		lf->srs = geo;
		free(wkt);
	}

	lf->bufrecs = LAS_BUFFER_BYTES / lf->reclen > 0 ? LAS_BUFFER_BYTES / lf->reclen : 1;
	lf->buf = malloc((size_t) lf->bufrecs * lf->reclen);
	if (lf->buf == NULL)
		las_fail(lf, "out of memory for a read buffer of %zu records", lf->bufrecs);
	if (fseeko(lf->f, (off_t) lf->point_offset, SEEK_SET) != 0)
		las_fail(lf, "cannot seek to the point data");
}

/*
 * The next records, at most max of them: the points whose class keep[]
 * holds (all when keep is NULL) into xy (pairs) and z; *k says how many.
 * False when no record is left.
 */
bool
las_next(las_file *lf, const unsigned char *keep, double *xy, double *z, size_t max, size_t *k)
{
	size_t		want = lf->bufrecs < max ? lf->bufrecs : max,
				m = 0;
	int			cbyte = lf->format >= 6 ? 16 : 15,
				cmask = lf->format >= 6 ? 0xFF : 0x1F;

	*k = 0;
	if (lf->done >= lf->n)
		return false;
	if (want > lf->n - lf->done)
		want = (size_t) (lf->n - lf->done);
	if (fread(lf->buf, lf->reclen, want, lf->f) != want)
		las_fail(lf, "truncated: the points end before the %llu the header says",
				 (unsigned long long) lf->n);
	lf->done += want;
	for (size_t i = 0; i < want; i++)
	{
		const unsigned char *r = lf->buf + i * lf->reclen;

		if (keep && !keep[r[cbyte] & cmask])
			continue;
		xy[2 * m] = (double) (int32_t) le32(r) * lf->scale[0] + lf->offset[0];
		xy[2 * m + 1] = (double) (int32_t) le32(r + 4) * lf->scale[1] + lf->offset[1];
		z[m] = (double) (int32_t) le32(r + 8) * lf->scale[2] + lf->offset[2];
		m++;
	}
	lf->kept += m;
	*k = m;
	return true;
}

/*
 * --stats with LAS input: one line, "las=1.4 format=6 points= kept= srs=",
 * the CRS as found (control characters as spaces) or "none".
 */
void
las_report(const las_file *lf)
{
	fprintf(stderr, "las=%d.%d format=%d points=%llu kept=%llu srs=", lf->major, lf->minor, lf->format,
			(unsigned long long) lf->n, (unsigned long long) lf->kept);
	if (lf->srs == NULL)
		fputs("none", stderr);
	for (const char *p = lf->srs; p && *p; p++)
		fputc((unsigned char) *p < 32 ? ' ' : *p, stderr);
	fputc('\n', stderr);
}

/* The file closed and the buffer freed; lf->srs stays, the caller's to free */
void
las_close(las_file *lf)
{
	fclose(lf->f);
	free(lf->buf);
	lf->f = NULL;
	lf->buf = NULL;
}
