/*
 * fn_voronoi.h
 *		The Voronoi functions' shared pieces (fn_voronoi.c), for the
 *		aggregate and the Dump function.
 */
#ifndef TDC_VORONOI_H
#define TDC_VORONOI_H

#include "tdc_pg.h"

typedef struct VorRun VorRun;

extern void tdc_voronoi_extend_to_box(Datum g, double ext[4],
									  const char *fname);
extern struct varlena *tdc_voronoi_to_value(const TdcPointBuf *buf, double tolerance,
											const double *ext, bool lines,
											const char *fname);
extern VorRun *tdc_voronoi_run(const TdcPointBuf *buf, double tolerance,
							   const double *ext, const tdc_cell_writer *writer,
							   TdcRun **runp, const char *fname);
extern const tdc_cell_writer tdc_polygon_cell_writer;
extern struct varlena *tdc_voronoi_write_polygons(VorRun *vrun, int32 srid,
												  uint64 have_bytes,
												  const char *fname);
extern const tdc_voronoi *tdc_voronoi_of(const VorRun *vrun);
extern void tdc_voronoi_result_free(VorRun *vrun, TdcRun *run);
extern struct varlena *tdc_voronoi_cell_value(const tdc_voronoi *v, uint32 site,
											  int32 srid);
extern struct varlena *tdc_voronoi_write_lines(const tdc_job *job, const tdc_voronoi *v,
											   int32 srid, uint64 have_bytes,
											   const char *fname);

#endif							/* TDC_VORONOI_H */
