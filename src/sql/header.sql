-- The install script of tdc_delaunay, made by the Makefile from the files of
-- src/sql/ in the order of its SQL_SRCS: edit those, not this.

-- complain if script is sourced in psql, rather than via CREATE EXTENSION
\echo Use "CREATE EXTENSION tdc_delaunay" to load this file. \quit
