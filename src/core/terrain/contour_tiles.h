/*
 * contour_tiles.h
 *		The state of contours in tiles (tdc_contour_tiles_*, tdc.h): the
 *		chains each tile writes (contour_tiles.c) and the join after the
 *		last tile (contour_join.c).  Private to terrain/.
 */
#ifndef TDC_TERRAIN_CONTOUR_TILES_H
#define TDC_TERRAIN_CONTOUR_TILES_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include "tdc.h"

/*
 * A chain: the maximal run of one level's segments through one tile's
 * triangles, as it lies in the chains file.  Its ends are crossing keys:
 * the level and the edge crossed (its two ends' coordinates, the first in
 * (x, y) order first), s where it enters (on the down edge of its first
 * triangle), e where it leaves (the up edge of its last).  Its points, n
 * x,y pairs (the crossing on s, then one per triangle), are at point off
 * of the points file.  A chain that closes within its tile has s = e.
 */
typedef struct ct_chain
{
	int64_t		k;
	double		s[4],
				e[4];
	uint64_t	off,
				n;
} ct_chain;

struct tdc_contour_tiles
{
	double		interval,
				base,
				max_edge;		/* > 0: the mask's */
	double		zmin,
				zmax;			/* over the sites of the tiles so far */
	size_t		ntri;			/* triangles seen */
	bool		too_fine;		/* a tile's heights failed the levels' check */
	char		dir[4096];
	int			pts_fd,
				chain_fd;		/* -1 when not open */
	FILE	   *pts,
			   *chains;			/* buffered writers on the two */
	char	   *pts_buf,
			   *chain_buf;
	uint64_t	npts,
				nchains;
	/*
	 * Two tiles may come at once (tdc_contour_tiles_tile is thread-safe):
	 * mu guards everything above; each call has its own histogram and
	 * windows, and writes a window's chains under mu, so that a chain's
	 * points stay together in the points file.
	 */
	pthread_mutex_t mu;
};

#define CT_HIST		65536		/* levels a tile counts at a time */
#define CT_BUF		((size_t) 256 << 10)	/* bytes of each file's write buffer */
#define CT_SEG_MIN	65536		/* segments a window may hold whatever the tile's size */

#endif							/* TDC_TERRAIN_CONTOUR_TILES_H */
