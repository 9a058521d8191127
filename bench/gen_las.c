/*
 * gen_las.c
 *		Synthetic airborne LiDAR as a LAS file, for ./tdc's LAS input
 *		(src/cli/las.c) in the benchmarks and the tests.
 *
 *	gen_las [-s SEED] [-d DENSITY] [-f FORMAT] [-v MINOR] SIDE OUT.las
 *
 * A square of SIDE metres (1e4 is read as 10000) in WGS 84 / UTM zone 32N
 * (EPSG:32632), its south-west corner at E 500000, N 5200000, sampled at
 * DENSITY points per square metre (default 10, what airborne surveys
 * deliver): one return per cell of a jittered grid of spacing
 * 1/sqrt(DENSITY), so the points are as even as a scanner's.  What a pulse
 * hits:
 *
 *	ground (class 2)	hills (a few long sine waves, 300 to 380 m) with
 *						3 cm of Gaussian noise, sloping down to a lake
 *	lake				an ellipse of 24% x 16% of SIDE centred at (0.3, 0.6)
 *						SIDE: no returns at all (water absorbs the pulse)
 *	buildings (6)		in blocks of 50 m, 4 in 10 hold one: 10-30 m by
 *						8-24 m, 4-25 m high, flat or gabled roof; the roof's
 *						points only, no ground under it
 *	vegetation (5)		woods where a smooth mask is high: 65% of the pulses
 *						return from the canopy (up to 25 m above the ground),
 *						the others from the ground (class 2) under it
 *
 * N is about DENSITY * SIDE^2 * 0.97 (the lake takes 3%): SIDE 10000 at 10
 * per square metre is 970 million points.  The points are streamed row by
 * row (south to north, west to east in a row), like the swaths of a
 * survey, so memory does not grow with N; the header's counts and bounds
 * are written last (OUT must be seekable).
 *
 * The file: LAS 1.MINOR (2, 3 or 4; default 4), point data record format
 * FORMAT (0 to 10; default 6, what LAS 1.4 prefers), the ASPRS LAS 1.4 R15
 * layout (header §2.4, VLRs §2.5, records §2.6), scale 0.01 m, offset the
 * corner.  Return 1 of 1; other fields 0.  CRS: formats 6 to 10 in a 1.4
 * file a WKT VLR (LASF_Projection 2112) with the WKT bit set, as §2.2
 * requires; otherwise a GeoKey directory (34735: GTModelTypeGeoKey 1
 * "projected", ProjectedCSTypeGeoKey 32632, ProjLinearUnitsGeoKey 9001
 * "metre").
 *
 * splitmix64 seeded with SEED: the output is a pure function of the
 * arguments.  Build: cc -O2 -o build/gen_las bench/gen_las.c -lm
 */
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../test/splitmix.h"

#define E0 500000.0
#define N0 5200000.0
#define BLOCK 50.0

static const char wkt_32632[] =
"PROJCS[\"WGS 84 / UTM zone 32N\",GEOGCS[\"WGS 84\",DATUM[\"WGS_1984\","
"SPHEROID[\"WGS 84\",6378137,298.257223563,AUTHORITY[\"EPSG\",\"7030\"]],AUTHORITY[\"EPSG\",\"6326\"]],"
"PRIMEM[\"Greenwich\",0,AUTHORITY[\"EPSG\",\"8901\"]],UNIT[\"degree\",0.0174532925199433,AUTHORITY[\"EPSG\",\"9122\"]],"
"AUTHORITY[\"EPSG\",\"4326\"]],PROJECTION[\"Transverse_Mercator\"],PARAMETER[\"latitude_of_origin\",0],"
"PARAMETER[\"central_meridian\",9],PARAMETER[\"scale_factor\",0.9996],PARAMETER[\"false_easting\",500000],"
"PARAMETER[\"false_northing\",0],UNIT[\"metre\",1,AUTHORITY[\"EPSG\",\"9001\"]],AXIS[\"Easting\",EAST],"
"AXIS[\"Northing\",NORTH],AUTHORITY[\"EPSG\",\"32632\"]]";

/* the minimum record size of each format (R15 §2.6) */
static const unsigned format_size[11] = {20, 28, 26, 34, 57, 63, 30, 36, 38, 59, 67};

/* The landscape: its phases and the lake, from the seed */
typedef struct land
{
	uint64_t	seed;
	double		side,
				ph[8],			/* phases of the hills and the woods */
				lx,				/* the lake: centre, radii, water level */
				ly,
				rx,
				ry,
				level;
} land;

static void
put16(unsigned char *p, unsigned v)
{
	p[0] = (unsigned char) v;
	p[1] = (unsigned char) (v >> 8);
}

static void
put32(unsigned char *p, uint32_t v)
{
	put16(p, v & 0xFFFF);
	put16(p + 2, v >> 16);
}

static void
put64(unsigned char *p, uint64_t v)
{
	put32(p, (uint32_t) v);
	put32(p + 4, (uint32_t) (v >> 32));
}

static void
putd(unsigned char *p, double d)
{
	uint64_t	u;

	memcpy(&u, &d, 8);
	put64(p, u);
}

/* The hills, before the lake's basin */
static double
hills(const land *l, double x, double y)
{
	const double tau = 2 * M_PI;

	return 340 + 22 * sin(tau * x / 1300 + l->ph[0]) * cos(tau * y / 900 + l->ph[1])
		+ 12 * sin(tau * (x + y) / 610 + l->ph[2]) + 4 * sin(tau * (x - 2 * y) / 230 + l->ph[3]);
}

/*
 * How far outside the lake's ellipse (x, y) is, in units of its radii: < 1
 * inside.
 */
static double
lake_r(const land *l, double x, double y)
{
	double		dx = (x - l->lx) / l->rx,
				dy = (y - l->ly) / l->ry;

	return sqrt(dx * dx + dy * dy);
}

/* The ground: the hills, sloping to the water level within 60% of the radii of the shore */
static double
ground(const land *l, double x, double y)
{
	double		h = hills(l, x, y),
				r = lake_r(l, x, y);

	if (r < 1.6)
	{
		double		t = r <= 1 ? 0 : (r - 1) / 0.6;

		t = t * t * (3 - 2 * t);
		h = l->level + 0.3 + (h - l->level - 0.3) * t;
	}
	return h;
}

/* The woods: a smooth mask, high in patches over about a fifth of the land */
static bool
woods(const land *l, double x, double y)
{
	const double tau = 2 * M_PI;

	return sin(tau * x / 700 + l->ph[4]) * sin(tau * y / 520 + l->ph[5])
		+ 0.5 * sin(tau * (x - y) / 330 + l->ph[6]) > 0.55;
}

/* The canopy's height over the ground, 12 to 25 m */
static double
canopy(const land *l, double x, double y)
{
	return 18.5 + 6.5 * sin(2 * M_PI * (x + 0.5 * y) / 170 + l->ph[7]);
}

/*
 * The building of the block holding (x, y), if (x, y) is on its roof:
 * true with the roof's height.  Each block's building is drawn from its
 * own generator, so no list of them is kept.
 */
static bool
roof(const land *l, double x, double y, double *z)
{
	int64_t		bi = (int64_t) floor(x / BLOCK),
				bj = (int64_t) floor(y / BLOCK);
	uint64_t	s = l->seed * UINT64_C(0x9E3779B97F4A7C15) ^ (uint64_t) bi * UINT64_C(0xC2B2AE3D27D4EB4F) ^
		(uint64_t) bj * UINT64_C(0x165667B19E3779F9);
	double		cx = (bi + 0.5) * BLOCK,
				cy = (bj + 0.5) * BLOCK,
				w,
				d,
				x0,
				y0,
				base,
				height;
	bool		gable;

	if (tdc_splitmix_unit(&s) >= 0.4 || lake_r(l, cx, cy) < 2.0 || woods(l, cx, cy))
		return false;
	w = 10 + 20 * tdc_splitmix_unit(&s);
	d = 8 + 16 * tdc_splitmix_unit(&s);
	x0 = bi * BLOCK + 5 + (BLOCK - 10 - w) * tdc_splitmix_unit(&s);
	y0 = bj * BLOCK + 5 + (BLOCK - 10 - d) * tdc_splitmix_unit(&s);
	height = 4 + 21 * tdc_splitmix_unit(&s);
	gable = tdc_splitmix_unit(&s) < 0.5;
	if (x < x0 || x >= x0 + w || y < y0 || y >= y0 + d)
		return false;
	base = ground(l, x0 + w / 2, y0 + d / 2);
	/* a gable's ridge runs east-west along the middle, 40% of the height over the eaves */
	*z = base + height - (gable ? 0.8 * height * fabs(y - (y0 + d / 2)) / d : 0);
	return true;
}

/* The header (R15 §2.4), its counts and bounds as known so far */
static size_t
header(unsigned char *h, int minor, int format, unsigned reclen, uint32_t offset, unsigned nvlr,
	   uint64_t n, const double mn[3], const double mx[3])
{
	size_t		hsize = minor == 2 ? 227 : minor == 3 ? 235 : 375;
	bool		legacy = format < 6 && n <= UINT32_MAX;

	memset(h, 0, 375);
	memcpy(h, "LASF", 4);
	put16(h + 6, minor == 4 && format >= 6 ? 16 : 0);	/* WKT bit */
	h[24] = 1;
	h[25] = (unsigned char) minor;
	memcpy(h + 26, "tdc bench/gen_las", 17);
	memcpy(h + 58, "gen_las", 7);
	put16(h + 90, 1);
	put16(h + 92, 2025);
	put16(h + 94, (unsigned) hsize);
	put32(h + 96, offset);
	put32(h + 100, nvlr);
	h[104] = (unsigned char) format;
	put16(h + 105, reclen);
	put32(h + 107, legacy || minor < 4 ? (uint32_t) n : 0);
	put32(h + 111, legacy || minor < 4 ? (uint32_t) n : 0);	/* all first returns */
	for (int c = 0; c < 3; c++)
	{
		putd(h + 131 + 8 * c, 0.01);
		putd(h + 179 + 16 * c, mx[c]);
		putd(h + 187 + 16 * c, mn[c]);
	}
	putd(h + 155, E0);
	putd(h + 163, N0);
	putd(h + 171, 0);
	if (minor == 4)
	{
		put64(h + 247, n);
		put64(h + 255, n);
	}
	return hsize;
}

/* The CRS record (R15 §2.5, §3): into v, returns its size */
static size_t
crs_vlr(unsigned char *v, int minor, int format)
{
	size_t		len;

	memset(v, 0, 54);
	memcpy(v + 2, "LASF_Projection", 15);
	if (minor == 4 && format >= 6)
	{
		len = sizeof(wkt_32632);	/* with its NUL */
		put16(v + 18, 2112);
		memcpy(v + 54, wkt_32632, len);
		memcpy(v + 22, "OGC WKT (EPSG:32632)", 20);
	}
	else
	{
		static const unsigned keys[] = {1, 1, 0, 3, 1024, 0, 1, 1, 3072, 0, 1, 32632, 3076, 0, 1, 9001};

		len = sizeof(keys) / sizeof(keys[0]) * 2;
		put16(v + 18, 34735);
		for (size_t i = 0; i < len / 2; i++)
			put16(v + 54 + 2 * i, keys[i]);
		memcpy(v + 22, "GeoKeyDirectoryTag", 18);
	}
	put16(v + 20, (unsigned) len);
	return 54 + len;
}

static void
usage(void)
{
	fprintf(stderr, "usage: gen_las [-s SEED] [-d DENSITY] [-f FORMAT] [-v MINOR] SIDE OUT.las\n");
	exit(2);
}

static double
number(const char *s)
{
	char	   *end;
	double		v;

	errno = 0;
	v = strtod(s, &end);
	if (errno || *end || !(v > 0) || !isfinite(v))
		usage();
	return v;
}

int
main(int argc, char **argv)
{
	land		l = {0};
	double		density = 10,
				h,
				mn[3] = {INFINITY, INFINITY, INFINITY},
				mx[3] = {-INFINITY, -INFINITY, -INFINITY};
	int			format = 6,
				minor = 4,
				opt;
	unsigned	reclen;
	unsigned char hdr[375],
				vlr[54 + sizeof(wkt_32632)],
			   *buf;
	size_t		hsize,
				vsize,
				inbuf = 0,
				cells;
	uint64_t	rng,
				n = 0,
				count[3] = {0};	/* ground, building, vegetation */
	FILE	   *f;

	while ((opt = getopt(argc, argv, "s:d:f:v:")) != -1)
	{
		if (opt == 's')
			l.seed = strtoull(optarg, NULL, 10);
		else if (opt == 'd')
			density = number(optarg);
		else if (opt == 'f')
			format = atoi(optarg);
		else if (opt == 'v')
			minor = atoi(optarg);
		else
			usage();
	}
	if (argc - optind != 2 || format < 0 || format > 10 || minor < 2 || minor > 4)
		usage();
	l.side = number(argv[optind]);
	if (l.side * 100 >= 2147483647.0)
	{
		fprintf(stderr, "gen_las: SIDE must be under 21474836 m (int32 centimetres)\n");
		return 2;
	}
	rng = l.seed ^ UINT64_C(0x5DEECE66D2B7E151);
	for (int i = 0; i < 8; i++)
		l.ph[i] = 2 * M_PI * tdc_splitmix_unit(&rng);
	l.lx = 0.3 * l.side;
	l.ly = 0.6 * l.side;
	l.rx = 0.12 * l.side;
	l.ry = 0.08 * l.side;
	l.level = hills(&l, l.lx, l.ly) - 2;

	f = fopen(argv[optind + 1], "wb");
	if (f == NULL)
	{
		perror(argv[optind + 1]);
		return 1;
	}
	reclen = format_size[format];
	vsize = crs_vlr(vlr, minor, format);
	hsize = header(hdr, minor, format, reclen, 0, 1, 0, mn, mx);
	if (fwrite(hdr, 1, hsize, f) != hsize || fwrite(vlr, 1, vsize, f) != vsize)
	{
		perror(argv[optind + 1]);
		return 1;
	}

	buf = calloc(4096, reclen);
	if (buf == NULL)
	{
		fprintf(stderr, "gen_las: out of memory\n");
		return 1;
	}
	h = 1 / sqrt(density);
	cells = (size_t) ceil(l.side / h);
	for (size_t j = 0; j < cells; j++)
	{
		for (size_t i = 0; i < cells; i++)
		{
			double		x = (i + tdc_splitmix_unit(&rng)) * h,
						y = (j + tdc_splitmix_unit(&rng)) * h,
						u = tdc_splitmix_unit(&rng),
						v = tdc_splitmix_unit(&rng),
						w = tdc_splitmix_unit(&rng),
						noise = 0.03 * sqrt(-2 * log(1 - u)) * cos(2 * M_PI * v),
						z;
			int			cls;
			int32_t		q[3];
			unsigned char *r;

			if (x >= l.side || y >= l.side || lake_r(&l, x, y) < 1)
				continue;
			if (roof(&l, x, y, &z))
				cls = 6, z += noise;
			else if (woods(&l, x, y) && w < 0.65)
				cls = 5, z = ground(&l, x, y) + canopy(&l, x, y) * sqrt(w / 0.65);
			else
				cls = 2, z = ground(&l, x, y) + noise;
			count[cls == 2 ? 0 : cls == 6 ? 1 : 2]++;
			q[0] = (int32_t) llround(x * 100);
			q[1] = (int32_t) llround(y * 100);
			q[2] = (int32_t) llround(z * 100);
			r = buf + inbuf * reclen;
			for (int c = 0; c < 3; c++)
			{
				double		a = q[c] * 0.01 + (c == 0 ? E0 : c == 1 ? N0 : 0);

				put32(r + 4 * c, (uint32_t) q[c]);
				mn[c] = a < mn[c] ? a : mn[c];
				mx[c] = a > mx[c] ? a : mx[c];
			}
			r[14] = format >= 6 ? 0x11 : 0x09;	/* return 1 of 1 */
			r[format >= 6 ? 16 : 15] = (unsigned char) cls;
			if (++inbuf == 4096)
			{
				if (fwrite(buf, reclen, inbuf, f) != inbuf)
				{
					perror(argv[optind + 1]);
					return 1;
				}
				inbuf = 0;
			}
			n++;
		}
	}
	if (fwrite(buf, reclen, inbuf, f) != inbuf)
	{
		perror(argv[optind + 1]);
		return 1;
	}
	if (minor < 4 && n > UINT32_MAX)
	{
		fprintf(stderr, "gen_las: %llu points do not fit LAS 1.%d's 32-bit count: take -v 4\n",
				(unsigned long long) n, minor);
		return 1;
	}
	if (n == 0)
		memset(mn, 0, sizeof(mn)), memset(mx, 0, sizeof(mx));
	header(hdr, minor, format, reclen, (uint32_t) (hsize + vsize), 1, n, mn, mx);
	if (fseek(f, 0, SEEK_SET) != 0 || fwrite(hdr, 1, hsize, f) != hsize || fclose(f) != 0)
	{
		perror(argv[optind + 1]);
		return 1;
	}
	free(buf);
	fprintf(stderr, "gen_las: %llu points: %llu ground, %llu building, %llu vegetation\n",
			(unsigned long long) n, (unsigned long long) count[0], (unsigned long long) count[1],
			(unsigned long long) count[2]);
	return 0;
}
