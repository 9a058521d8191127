-- src/sql/diagnostics.sql: functions the tests use to look inside the library

-- Diagnostics

CREATE FUNCTION _st_tdcdelaunay_state_check(bytea)
RETURNS bigint
AS 'MODULE_PATHNAME', '_st_tdcdelaunay_state_check'
LANGUAGE C IMMUTABLE STRICT PARALLEL SAFE;

COMMENT ON FUNCTION _st_tdcdelaunay_state_check(bytea) IS
'Diagnostic: validates a serialized ST_TDCDelaunay aggregate state as the parallel deserialization function does '
'(raising an error when it is corrupt) and returns its vertex count.';

CREATE FUNCTION _tdc_signal_tls_ready()
RETURNS boolean
AS 'MODULE_PATHNAME', '_tdc_signal_tls_ready'
LANGUAGE C VOLATILE PARALLEL RESTRICTED;

COMMENT ON FUNCTION _tdc_signal_tls_ready() IS
'Diagnostic: true when every loaded library''s thread-local block is allocated for this backend''s main thread, '
'which tdc_delaunay arranges at its first call so that PostGIS''s cancel handler never allocates inside a signal.';
