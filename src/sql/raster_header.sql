-- The install script of tdc_delaunay_raster, made by the Makefile from
-- src/sql/raster_header.sql and src/sql/raster.sql: edit those, not this.
-- A second extension in the tdc_delaunay package, so that CREATE EXTENSION
-- tdc_delaunay never needs postgis_raster; its functions are in the same
-- library (module_pathname of tdc_delaunay_raster.control).

-- complain if script is sourced in psql, rather than via CREATE EXTENSION
\echo Use "CREATE EXTENSION tdc_delaunay_raster" to load this file. \quit
