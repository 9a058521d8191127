/*
 * tile_cells.h
 *		The cells of a tile's grid (tdc_tile_grid in tdc.h) as the finality
 *		check of tile_final.c reads them: which OTHER cells (cells whose
 *		points the tile was not given) a circumdisk or the outer half-plane
 *		of a hull edge meets.
 *
 * A known box is the right shape for a tile of uniform points; on a
 * coastline or between clusters it is not.  A triangle in the sea between
 * two coasts has a circumdisk far larger than the local spacing, empty of
 * points, whose bounding box holds whole stretches of dense coast: growing K
 * to it reads them all.  The cells say where P has no point, so such a disk
 * is known once the few cells along its rim that hold points are, and a
 * tile that is not final names those cells rather than a box.
 */
#ifndef TDC_TILE_CELLS_H
#define TDC_TILE_CELLS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "tdc.h"

/* The grid with the prefix sums of its OTHER cells. */
typedef struct tdc_cells
{
	const tdc_tile_grid *g;
	uint32_t   *ps;				/* (nx + 1) x (ny + 1) */
} tdc_cells;

/* A growing list of cell indices (j * nx + i); failed once out of memory. */
typedef struct tdc_cell_list
{
	uint32_t   *v;
	size_t		n,
				cap;
	bool		failed;
} tdc_cell_list;

/* Whether the closed box is known otherwise (inside K or the extra boxes). */
typedef bool (*tdc_cells_covered_fn) (const void *arg, const double box[4]);

extern bool tdc_cells_init(tdc_cells *c, const tdc_tile_grid *g);
extern void tdc_cells_free(tdc_cells *c);
extern bool tdc_cells_point_known(const tdc_cells *c, const double *p);
extern bool tdc_cells_disk(const tdc_cells *c, const double disk[3], const double clip[4],
						   const double *near, int nnear,
						   tdc_cells_covered_fn covered, const void *arg, tdc_cell_list *out);
extern bool tdc_cells_beyond(const tdc_cells *c, const double *a, const double *b,
							 tdc_cells_covered_fn covered, const void *arg, tdc_cell_list *out);
extern bool tdc_cells_merge(const tdc_cells *c, tdc_cell_list *lists, int nlists,
							uint32_t **cells, size_t *ncells);

#endif							/* TDC_TILE_CELLS_H */
