/*
 * gshhg_convert.c
 *		Convert the multi-segment text written by
 *			gmt coast -Rd -Df -W -M
 *		(lines "lon<TAB>lat", segments separated by lines starting with '>')
 *		into the benchmark inputs.
 *
 *	gshhg_convert IN.txt OUT_PREFIX SUBSET_N SEED
 *
 * writes
 *	OUT_PREFIX.bin			every vertex, in file order, as raw little-endian
 *							float64 lon,lat pairs (input of ./tdc and CGAL)
 *	OUT_PREFIX_lines.ewkt	one "SRID=4326;LINESTRING(...)" per segment, for
 *							COPY into a geometry column
 *	OUT_PREFIX_sub.bin		SUBSET_N vertices drawn without replacement
 *							(deterministic, splitmix64 seeded by SEED)
 *	OUT_PREFIX_sub.tsv		the same subset as "lon<TAB>lat" lines for COPY
 * and prints "segments=S vertices=V min_seg=A max_seg=B subset=K" to stdout.
 * Numbers are printed with the fewest digits that read back to the same
 * double, so the SQL tables and the .bin files hold identical coordinates.
 *
 * Build: cc -O2 -o build/gshhg_convert bench/gshhg_convert.c
 */
#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../test/splitmix.h"

static uint64_t rng_state;

static uint64_t
rng_below(uint64_t bound)
{
	return tdc_splitmix_below(&rng_state, bound);
}

/* shortest %.*g representation that round-trips */
static void
put_double(FILE *f, double v)
{
	char		buf[40];

	for (int prec = 12; prec <= 17; prec++)
	{
		snprintf(buf, sizeof buf, "%.*g", prec, v);
		if (prec == 17 || strtod(buf, NULL) == v)
			break;
	}
	fputs(buf, f);
}

static FILE *
open_out(const char *prefix, const char *suffix, const char *mode)
{
	size_t		len = strlen(prefix) + strlen(suffix) + 1;
	char	   *path = malloc(len);
	FILE	   *f;

	if (!path)
		exit(1);
	snprintf(path, len, "%s%s", prefix, suffix);
	f = fopen(path, mode);
	if (!f)
	{
		fprintf(stderr, "gshhg_convert: cannot open %s: %s\n", path, strerror(errno));
		exit(1);
	}
	free(path);
	return f;
}

int
main(int argc, char **argv)
{
	FILE	   *in,
			   *fbin,
			   *fwkt,
			   *fsb,
			   *fst;
	char		line[4096];
	double	   *xy = NULL;
	size_t		cap = 0,
				nv = 0,
				nseg = 0,
				seg_start = 0,
				min_seg = SIZE_MAX,
				max_seg = 0,
				nsub;
	char	   *end;

	if (argc != 5)
	{
		fprintf(stderr, "usage: %s IN.txt OUT_PREFIX SUBSET_N SEED\n", argv[0]);
		return 2;
	}
	nsub = (size_t) strtod(argv[3], &end);
	if (*end)
	{
		fprintf(stderr, "gshhg_convert: bad SUBSET_N\n");
		return 2;
	}
	rng_state = strtoull(argv[4], NULL, 10) ^ UINT64_C(0x5DEECE66D2B7E151);

	in = strcmp(argv[1], "-") == 0 ? stdin : fopen(argv[1], "r");
	if (!in)
	{
		fprintf(stderr, "gshhg_convert: cannot open %s: %s\n", argv[1], strerror(errno));
		return 1;
	}

	/* read all vertices, remembering segment boundaries by a NaN marker */
	while (fgets(line, sizeof line, in))
	{
		double		x,
					y;
		char	   *p;

		if (line[0] == '>' || line[0] == '#')
		{
			if (line[0] == '>' && nv > 0)
			{
				/* marker between segments: NaN pair */
				if (nv + 1 > cap)
				{
					cap = cap ? 2 * cap : (1 << 20);
					xy = realloc(xy, cap * 2 * sizeof(double));
					if (!xy)
						return 1;
				}
				xy[2 * nv] = xy[2 * nv + 1] = __builtin_nan("");
				nv++;
			}
			continue;
		}
		errno = 0;
		x = strtod(line, &p);
		if (p == line)
			continue;			/* blank line */
		y = strtod(p, &end);
		if (end == p || errno)
		{
			fprintf(stderr, "gshhg_convert: bad line: %s", line);
			return 1;
		}
		if (nv + 1 > cap)
		{
			cap = cap ? 2 * cap : (1 << 20);
			xy = realloc(xy, cap * 2 * sizeof(double));
			if (!xy)
				return 1;
		}
		xy[2 * nv] = x;
		xy[2 * nv + 1] = y;
		nv++;
	}
	if (in != stdin)
		fclose(in);

	fbin = open_out(argv[2], ".bin", "wb");
	fwkt = open_out(argv[2], "_lines.ewkt", "w");

	/* pass over segments: EWKT lines and compacted vertex array */
	{
		size_t		w = 0;
		size_t		cnt = 0;

		for (size_t i = 0; i <= nv; i++)
		{
			int			brk = (i == nv) || (xy[2 * i] != xy[2 * i]);

			if (brk)
			{
				if (cnt > 0)
				{
					fputs(cnt >= 2 ? "SRID=4326;LINESTRING(" : "SRID=4326;POINT(", fwkt);
					for (size_t j = seg_start; j < seg_start + cnt; j++)
					{
						if (j > seg_start)
							fputc(',', fwkt);
						put_double(fwkt, xy[2 * j]);
						fputc(' ', fwkt);
						put_double(fwkt, xy[2 * j + 1]);
					}
					fputs(")\n", fwkt);
					nseg++;
					if (cnt < min_seg)
						min_seg = cnt;
					if (cnt > max_seg)
						max_seg = cnt;
				}
				seg_start = w;
				cnt = 0;
				continue;
			}
			xy[2 * w] = xy[2 * i];
			xy[2 * w + 1] = xy[2 * i + 1];
			w++;
			cnt++;
		}
		nv = w;
	}
	if (fwrite(xy, 2 * sizeof(double), nv, fbin) != nv || fclose(fbin) || fclose(fwkt))
	{
		fprintf(stderr, "gshhg_convert: write error\n");
		return 1;
	}

	/* subset: partial Fisher-Yates over the vertex array */
	if (nsub > nv)
		nsub = nv;
	for (size_t i = 0; i < nsub; i++)
	{
		size_t		j = i + (size_t) rng_below(nv - i);
		double		tx = xy[2 * i],
					ty = xy[2 * i + 1];

		xy[2 * i] = xy[2 * j];
		xy[2 * i + 1] = xy[2 * j + 1];
		xy[2 * j] = tx;
		xy[2 * j + 1] = ty;
	}
	fsb = open_out(argv[2], "_sub.bin", "wb");
	fst = open_out(argv[2], "_sub.tsv", "w");
	for (size_t i = 0; i < nsub; i++)
	{
		put_double(fst, xy[2 * i]);
		fputc('\t', fst);
		put_double(fst, xy[2 * i + 1]);
		fputc('\n', fst);
	}
	if (fwrite(xy, 2 * sizeof(double), nsub, fsb) != nsub || fclose(fsb) || fclose(fst))
	{
		fprintf(stderr, "gshhg_convert: write error\n");
		return 1;
	}
	printf("segments=%zu vertices=%zu min_seg=%zu max_seg=%zu subset=%zu\n",
		   nseg, nv, min_seg == SIZE_MAX ? 0 : min_seg, max_seg, nsub);
	free(xy);
	return 0;
}
