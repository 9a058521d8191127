/*
 * fn_raster.h
 *		The raster functions' shared pieces (fn_raster.c), for the
 *		ST_TDCInterpolate aggregates (fn_raster_agg.c).
 */
#ifndef TDC_FN_RASTER_H
#define TDC_FN_RASTER_H

#include "tdc_pg.h"
#include "formats/raster_format.h"

extern void tdc_raster_method(const char *method, tdc_interp_spec *spec,
							  const char *fname);
extern bool tdc_raster_method_sets_nodata(const char *method);
extern bool tdc_raster_breaklines(const tdc_interp_spec *spec, TdcSegList *l,
								  MemoryContext cxt, TdcPointBuf *pts,
								  const char *fname);
extern struct varlena *tdc_raster_interpolate(const TdcPointBuf *pts,
											  const TdcSegList *breaklines,
											  const TdcRasterInfo *tmpl,
											  const char *method,
											  const char *fname);

#endif							/* TDC_FN_RASTER_H */
