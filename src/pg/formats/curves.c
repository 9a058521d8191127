/*
 * curves.c
 *		Curved input of the Delaunay functions, stroked by PostGIS itself.
 *
 * ST_DelaunayTriangles hands its input to GEOS, and PostGIS converts a
 * geometry with arcs for GEOS by stroking it first, 32 segments to a
 * quarter circle.  ST_CurveToLine with its default arguments strokes with
 * the same liblwgeom code and the same count, so the triangles of
 * ST_DelaunayTriangles(g) are those of ST_DelaunayTriangles(ST_CurveToLine(g)),
 * bit for bit (tdc_postgis_cases checks it).  So a Delaunay function of
 * ours that meets a curve (TDC_CURVES_STROKE) calls ST_CurveToLine on the
 * whole value and reads the result instead: the same vertices as PostGIS,
 * with no stroking arithmetic of our own to drift from it.  The reader
 * (gser_read.c) only notices the curve, drops what it had read of that
 * value, and comes here.
 *
 * The other families follow their PostGIS or SFCGAL counterparts too:
 * ST_VoronoiPolygons reads a curve's vertices as they are stored (its
 * control points: GEOS gets the coordinates, not the arcs), and so do our
 * Voronoi functions (TDC_CURVES_VERTICES); SFCGAL refuses curves, and so do
 * the constrained functions (TDC_CURVES_REFUSE, with a hint).
 *
 * The function is found through its catalog entry: the C function
 * ST_CurveToLine of four arguments, in whatever schema PostGIS lives in.
 * Only a superuser can create a C function, so no user's function can stand
 * in for it through the search path.  Its OID is kept for the session and
 * looked up again if it is gone (PostGIS dropped and created again).
 */
#include "postgres.h"

#include "access/htup_details.h"
#include "catalog/pg_language.h"
#include "catalog/pg_proc.h"
#include "fmgr.h"
#include "utils/builtins.h"
#include "utils/catcache.h"
#include "utils/memutils.h"
#include "utils/syscache.h"

#include "tdc_pg.h"

/* ST_CurveToLine's defaults: tolerance 32 of type 0, segments per quadrant */
#define STROKE_SEGMENTS_PER_QUADRANT	32.0

static Oid	curvetoline_oid = InvalidOid;

static Oid
find_curvetoline(const char *fname)
{
	CatCList   *list;
	Oid			fn = InvalidOid;

	list = SearchSysCacheList1(PROCNAMEARGSNSP, CStringGetDatum("st_curvetoline"));
	for (int i = 0; i < list->n_members && !OidIsValid(fn); i++)
	{
		HeapTuple	tup = &list->members[i]->tuple;
		Form_pg_proc p = (Form_pg_proc) GETSTRUCT(tup);
		bool		isnull;
		Datum		src;

		if (p->prolang != ClanguageId || p->pronargs != 4)
			continue;
		src = SysCacheGetAttr(PROCOID, tup, Anum_pg_proc_prosrc, &isnull);
		if (!isnull && strcmp(TextDatumGetCString(src), "ST_CurveToLine") == 0)
			fn = p->oid;
	}
	ReleaseSysCacheList(list);
	if (!OidIsValid(fn))
		ereport(ERROR,
				(errcode(ERRCODE_UNDEFINED_FUNCTION),
				 errmsg("%s: the input has curves, and PostGIS's ST_CurveToLine, which strokes them, was not found",
						fname)));
	return fn;
}

/*
 * geom (any varlena form of a geometry with curves) stroked as
 * ST_DelaunayTriangles strokes it: a new value, in the current memory
 * context, with the same SRID and dimensions and no curves.
 */
struct varlena *
tdc_curve_to_line(Datum geom, const char *fname)
{
	if (!OidIsValid(curvetoline_oid) ||
		!SearchSysCacheExists1(PROCOID, ObjectIdGetDatum(curvetoline_oid)))
		curvetoline_oid = find_curvetoline(fname);
	return (struct varlena *)
		PG_DETOAST_DATUM(OidFunctionCall4(curvetoline_oid, geom,
										  Float8GetDatum(STROKE_SEGMENTS_PER_QUADRANT),
										  Int32GetDatum(0), Int32GetDatum(0)));
}
