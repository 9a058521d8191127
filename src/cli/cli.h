/*
 * cli.h
 *		What the two files of ./tdc share: the front end (tdc.c) and the
 *		tiled run of --max-memory (tiled.c).  Not installed.
 */
#ifndef TDC_CLI_H
#define TDC_CLI_H

#include <stdio.h>
#include <stddef.h>

#include "tdc.h"

/* Counts and wall times of a tiled run, for --stats. */
typedef struct tiled_stats
{
	size_t		n,
				unique,
				ntri,
				halo,
				runs;
	int			tiles,
				threads;
	tdc_times	t;
	double		scan,			/* wall seconds: box, hull and counts */
				bin,			/* the points to the tile files */
				gather,			/* each tile's points read back */
				engine,			/* tdc_triangulate */
				finish,			/* tdc_tile_finish */
				write;			/* the triangles to -o, and the frees */
} tiled_stats;

/* tdc.c */
extern void die(int code, const char *fmt, const char *arg) __attribute__((noreturn));
extern int	parse_line(char *line, size_t lineno, double v[3], int *dims);

/* tiled.c: the temporary directory of the tiles, removed by tmp_cleanup */
extern char tmp_dir[4096];
extern void tmp_cleanup(void);
extern size_t text_to_bin(const char *path, int *has_z);
extern void run_tiled(const char *xypath, const char *zpath, size_t n, const tdc_options *opt,
					  size_t budget, FILE *out, tiled_stats *st);

#endif							/* TDC_CLI_H */
