/*
 * test/geotiff_rows.c: the GeoTIFF writer of ./tdc (src/cli/geotiff.c)
 * fed rows in pieces, for test/cli_geotiff.sh.
 *
 *	geotiff_rows OUT WIDTH HEIGHT PIECE...
 *
 * writes a WIDTH x HEIGHT Float64 grid whose pixel (col, row) holds
 * row * 1000 + col + 0.25 (nodata -9999 at every 7th pixel) to OUT, its
 * rows given to gtiff_write_rows in pieces of the PIECE counts in turn
 * (cycling; 0 means all the rows left at once).  The same grid written in
 * any pieces must give the same file, byte for byte: the script compares.
 *
 *	geotiff_rows --short OUT	closes a 10 x 600 grid after 300 rows
 *	geotiff_rows --order OUT	writes rows 0..9, then 20..29
 *
 * must fail with a message and leave neither OUT nor its temporary file.
 * Exit 0 on success, 1 on an expected failure (message on stderr), 2 on
 * misuse.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

static int
failed(const char *err)
{
	fprintf(stderr, "geotiff_rows: %s\n", err);
	return 1;
}

int
main(int argc, char **argv)
{
	char		err[1024];
	double		gt[6] = {1000, 2, 0, 5000, 0, -2};
	size_t		w,
				h,
				y = 0;
	int			k = 0;
	double	   *v;
	gtiff_out  *g;
	bool		shortw = argc == 3 && strcmp(argv[1], "--short") == 0,
				order = argc == 3 && strcmp(argv[1], "--order") == 0;

	if (shortw || order)
	{
		w = 10;
		h = 600;
	}
	else if (argc >= 5)
	{
		w = strtoul(argv[2], NULL, 10);
		h = strtoul(argv[3], NULL, 10);
	}
	else
	{
		fprintf(stderr, "usage: geotiff_rows OUT WIDTH HEIGHT PIECE... | --short OUT | --order OUT\n");
		return 2;
	}
	v = malloc(w * h * sizeof(double));
	if (v == NULL || w == 0 || h == 0)
		return 2;
	for (size_t r = 0; r < h; r++)
		for (size_t c = 0; c < w; c++)
			v[r * w + c] = (r * w + c) % 7 == 3 ? -9999 : r * 1000.0 + c + 0.25;
	if ((g = gtiff_reserve(argv[shortw || order ? 2 : 1], err, sizeof(err))) == NULL ||
		gtiff_open(g, w, h, gt, "EPSG:25832", -9999, false, 0, err, sizeof(err)) != 0)
		return failed(err);
	if (shortw)
	{
		if (gtiff_write_rows(g, 0, 300, v, err, sizeof(err)) != 0)
			return failed(err);
		return gtiff_close(g, err, sizeof(err)) != 0 ? failed(err) : 0;
	}
	if (order)
	{
		if (gtiff_write_rows(g, 0, 10, v, err, sizeof(err)) != 0 ||
			gtiff_write_rows(g, 20, 10, v + 20 * w, err, sizeof(err)) != 0)
			return failed(err);
		return gtiff_close(g, err, sizeof(err)) != 0 ? failed(err) : 0;
	}
	while (y < h)
	{
		size_t		n = strtoul(argv[4 + k % (argc - 4)], NULL, 10);

		if (n == 0 || n > h - y)
			n = h - y;
		if (gtiff_write_rows(g, y, n, v + y * w, err, sizeof(err)) != 0)
			return failed(err);
		y += n;
		k++;
	}
	if (gtiff_close(g, err, sizeof(err)) != 0)
		return failed(err);
	free(v);
	return 0;
}
