/*
 * tile_disk.h
 *		The rounded boxes of circumdisks that the finality check of
 *		tile_final.c takes (tile_disk.c explains their error bounds).
 */
#ifndef TDC_TILE_DISK_H
#define TDC_TILE_DISK_H

#include <stdbool.h>
#include <stddef.h>

/*
 * A box (xmin, ymin, xmax, ymax) that holds the closed circumdisk of
 * counter-clockwise a, b, c, and a disk (centre, radius) that holds it too;
 * false when the orientation is too uncertain to bound the centre.
 */
extern bool tdc_disk_box(const double *a, const double *b, const double *c,
						 double box[4], double disk[3]);

/* Shrink box, around disk, to the part of the disk on the closed left of a -> b. */
extern void tdc_disk_clip_box(const double *disk, const double *a, const double *b,
							  double box[4]);

/*
 * Shrink box, around the circumdisk of counter-clockwise a, b, c, to the
 * circular segment on c's side of a -> b, a certified global hull edge.
 */
extern void tdc_disk_segment_box(const double *a, const double *b, const double *c,
								 double box[4]);

/*
 * tile_final.c: is box r (xmin, ymin, xmax, ymax) covered by the union of
 * the closed boxes k[0..nk)?  Conservative: false may be a union too
 * fragmented to tell.  (Also for terrain/raster_natural.c's Lemma 1.)
 */
extern bool tdc_box_covered(const double *r, const double *const *k, size_t nk);

#endif							/* TDC_TILE_DISK_H */
