--
-- tdc_guc_units: out-of-range values of the settings that have a unit.
-- PostgreSQL 17 prints the unit with the bounds of the range too
-- ("(0 MB .. 2147483647 MB)"; 15 prints "(0 .. 2147483647)"), so this file
-- has a second expected output, tdc_guc_units_1.out; the other settings'
-- range errors, whose text is the same on every major, are in tdc_guc.
--
-- The settings exist once the library is loaded (by any function call).
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0, 1 0, 0 1)')) AS loaded;
SET tdc_delaunay.keep_memory = -1;
SET tdc_delaunay.max_memory = -1;
SET tdc_delaunay.memory_ceiling = -2;
SET tdc_delaunay.keep_memory_time = -1;
-- a rejected value leaves the setting as it was
SHOW tdc_delaunay.keep_memory;
SHOW tdc_delaunay.max_memory;
SHOW tdc_delaunay.memory_ceiling;
SHOW tdc_delaunay.keep_memory_time;
