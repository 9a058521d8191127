--
-- tdc_signal: after tdc_delaunay's first call in a backend, no signal
-- handler's first thread-local access can allocate memory (src/pg/runtime/signals.c).
--
-- PostGIS's SIGINT handler writes a thread-local flag.  In a backend where no
-- PostGIS code has touched it yet, glibc allocates the flag's block inside
-- the handler; a cancel that lands while the backend is in malloc then
-- corrupts the heap and the postmaster restarts every session (seen in a
-- cancel storm against fresh sessions).  Loading PostGIS through a type's
-- input function leaves the block unallocated, as our functions used to.
--
SELECT ST_AsText('POINT(0 0)'::geometry);
-- The first call of any tdc_delaunay entry point settles it for the backend.
SELECT ST_NumGeometries(ST_TDCDelaunayTriangles('MULTIPOINT(0 0,1 0,0 1)'));
SELECT _tdc_signal_tls_ready() AS tls_ready;
